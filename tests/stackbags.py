"""A bag of nav2's and vision_msgs' display topics, written by rosbags (its serializer and writer) with the
upstream .msg files (:mod:`stack_msgs`) registered in its own typestore: AMCL-like particles, a voxel layer's grid,
a camera with 2D detections and 3D detections. Every expected value in the tests is worked out by hand from what is
written here (or by numpy from the yaw angles written here, not from quaternions)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from stack_msgs import MSG_FILES

S = 1_000_000_000
T0 = 1_700_000_000 * S
STORE = get_typestore(Stores.ROS2_HUMBLE)
for _name, _text in MSG_FILES.items():
    STORE.register(get_types_from_msg(_text, _name))
TYPES = {
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/particlecloud": "nav2_msgs/msg/ParticleCloud",
    "/voxel_grid": "nav2_msgs/msg/VoxelGrid",
    "/cam/camera_info": "sensor_msgs/msg/CameraInfo",
    "/cam/image_raw": "sensor_msgs/msg/Image",
    "/cam/detections": "vision_msgs/msg/Detection2DArray",
    "/detections_3d": "vision_msgs/msg/Detection3DArray",
}
DETECTIONS_2D_ENTITY = "/cam/image_raw/detections/cam/detections"
"""Where the 2D detections go: below their camera's image entity."""

# (x, y, z, yaw rad, weight): the first four worked by hand in the tests; then a ring of 60 for the eye
PARTICLES = [(1.0, 2.0, 0.0, 0.0, 0.5), (0.0, 0.0, 0.5, math.pi / 2, 1.0), (-1.0, 0.0, 0.0, None, 2.0)]
PARTICLES += [(0.5, -1.0, 0.0, math.pi, -1.0)]
PARTICLES += [(2 * math.cos(a), 2 * math.sin(a), 0.0, a + math.pi / 2, (k % 10) / 10) for k, a in
              enumerate(np.linspace(0, 2 * math.pi, 60, endpoint=False))]  # fmt: skip
"""A yaw of None is written as the all-zero quaternion (read as identity)."""

VOXEL_SIZE = (3, 2, 4)
VOXEL_ORIGIN = (0.5, -0.5, 0.0)
VOXEL_RES = (0.2, 0.2, 0.25)
VOXEL_DATA = [0x00010009, 0x00040000, 0, 0, 0, 0x000A000A]
"""Column (0, 0): z 0 marked (bits 0 and 16), z 3 unknown (bit 3 alone); column (1, 0): z 2 unknown (bit 18
alone); column (2, 1) (index 1·3 + 2): z 1 and z 3 marked (bits 1, 17, 3, 19)."""
VOXEL_CENTERS = [(0.6, -0.4, 0.125), (1.0, -0.2, 0.375), (1.0, -0.2, 0.875)]
"""origin + (index + 0.5) · resolution of voxels (0, 0, 0), (2, 1, 1), (2, 1, 3), by hand."""

IMAGE_SIZE = (64, 48)
# (cx, cy, theta, size x, size y, results [(class_id, score)])
DETECTIONS_2D = [(20.0, 15.0, 0.0, 10.0, 6.0, [("person", 0.9), ("car", 0.3)]), (40.0, 30.0, math.pi / 2, 8.0, 4.0, [])]
DETECTIONS_2D_CORNERS = [
    [(15, 12), (25, 12), (25, 18), (15, 18)],
    [(42, 26), (42, 34), (38, 34), (38, 26)],  # turned 90°: (lx, ly) → (−ly, lx) about (40, 30)
]
# (x, y, z, yaw, size, results)
DETECTIONS_3D = [
    (2.0, 0.0, 0.5, math.pi / 2, (1.0, 0.5, 0.4), [("Car", 0.75)]),
    (-2.0, 1.0, 0.1, 0.0, (0.3, 0.0, 0.2), [("tree", 0.5), ("bush", 0.25)]),
]


def T(name: str):
    return STORE.types[name]


def _header(frame: str, t: int):
    return T("std_msgs/msg/Header")(T("builtin_interfaces/msg/Time")(*divmod(t, S)), frame)


def _quat(yaw: float | None):
    q = T("geometry_msgs/msg/Quaternion")
    return q(0.0, 0.0, 0.0, 0.0) if yaw is None else q(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def _pose(x: float, y: float, z: float, yaw: float | None):
    return T("geometry_msgs/msg/Pose")(T("geometry_msgs/msg/Point")(x, y, z), _quat(yaw))


def _cdr(msg, name: str) -> bytes:
    return bytes(STORE.serialize_cdr(msg, name))


def particle_cloud(t: int) -> bytes:
    particles = [T("nav2_msgs/msg/Particle")(_pose(x, y, z, yaw), w) for x, y, z, yaw, w in PARTICLES]
    return _cdr(T("nav2_msgs/msg/ParticleCloud")(_header("map", t), particles), "nav2_msgs/msg/ParticleCloud")


def voxel_grid(t: int) -> bytes:
    msg = T("nav2_msgs/msg/VoxelGrid")(
        _header("odom", t),
        np.array(VOXEL_DATA, dtype=np.uint32),
        T("geometry_msgs/msg/Point32")(*VOXEL_ORIGIN),
        T("geometry_msgs/msg/Vector3")(*VOXEL_RES),
        *VOXEL_SIZE,
    )
    return _cdr(msg, "nav2_msgs/msg/VoxelGrid")


def _results(results: list[tuple[str, float]]) -> list:
    cov = T("geometry_msgs/msg/PoseWithCovariance")(_pose(0, 0, 0, 0.0), np.zeros(36))
    hyp = T("vision_msgs/msg/ObjectHypothesis")
    return [T("vision_msgs/msg/ObjectHypothesisWithPose")(hyp(c, s), cov) for c, s in results]


def detections_2d(t: int) -> bytes:
    point, pose2d, box = T("vision_msgs/msg/Point2D"), T("vision_msgs/msg/Pose2D"), T("vision_msgs/msg/BoundingBox2D")
    detections = [
        T("vision_msgs/msg/Detection2D")(
            _header("cam_optical", t), _results(r), box(pose2d(point(x, y), th), sx, sy), ""
        )
        for x, y, th, sx, sy, r in DETECTIONS_2D
    ]
    msg = T("vision_msgs/msg/Detection2DArray")(_header("cam_optical", t), detections)
    return _cdr(msg, "vision_msgs/msg/Detection2DArray")


def detections_3d(t: int) -> bytes:
    box, vec = T("vision_msgs/msg/BoundingBox3D"), T("geometry_msgs/msg/Vector3")
    detections = [
        T("vision_msgs/msg/Detection3D")(_header("map", t), _results(r), box(_pose(x, y, z, yaw), vec(*size)), "")
        for x, y, z, yaw, size, r in DETECTIONS_3D
    ]
    return _cdr(
        T("vision_msgs/msg/Detection3DArray")(_header("map", t), detections), "vision_msgs/msg/Detection3DArray"
    )


def _tf_static(t: int) -> bytes:
    tf, v, q = (
        T("geometry_msgs/msg/TransformStamped"),
        T("geometry_msgs/msg/Vector3"),
        T("geometry_msgs/msg/Quaternion"),
    )
    optical = q(-0.5, 0.5, -0.5, 0.5)  # REP 103: z forward, x right, y down; looking along the map's +x
    edges = [
        tf(_header("map", t), "odom", T("geometry_msgs/msg/Transform")(v(0.0, 0.0, 0.0), q(0.0, 0.0, 0.0, 1.0))),
        tf(_header("map", t), "cam_optical", T("geometry_msgs/msg/Transform")(v(-4.0, 0.0, 1.0), optical)),
    ]
    return _cdr(T("tf2_msgs/msg/TFMessage")(edges), "tf2_msgs/msg/TFMessage")


def _camera(t: int) -> tuple[bytes, bytes]:
    w, h = IMAGE_SIZE
    k = np.array([40.0, 0, w / 2, 0, 40.0, h / 2, 0, 0, 1])
    p = np.array([40.0, 0, w / 2, 0, 0, 40.0, h / 2, 0, 0, 0, 1, 0])
    roi = T("sensor_msgs/msg/RegionOfInterest")(0, 0, 0, 0, False)
    info = T("sensor_msgs/msg/CameraInfo")(_header("cam_optical", t), h, w, "plumb_bob", np.zeros(5), k,
                                            np.eye(3).reshape(-1), p, 0, 0, roi)  # fmt: skip
    pixels = np.zeros((h, w, 3), dtype=np.uint8)
    pixels[:, :, 1] = np.arange(w, dtype=np.uint8)[None, :] * 3  # a green ramp
    image = T("sensor_msgs/msg/Image")(_header("cam_optical", t), h, w, "rgb8", 0, w * 3, pixels.reshape(-1))
    return _cdr(info, "sensor_msgs/msg/CameraInfo"), _cdr(image, "sensor_msgs/msg/Image")


def write_stack_bag(path: Path) -> Path:
    """Everything at T0 + 0.1 s (the transforms at T0), once."""
    t = T0 + S // 10
    info, image = _camera(t)
    messages = [("/tf_static", T0, _tf_static(T0)), ("/cam/camera_info", t, info), ("/cam/image_raw", t, image)]
    messages += [("/particlecloud", t, particle_cloud(t)), ("/voxel_grid", t, voxel_grid(t))]
    messages += [("/cam/detections", t, detections_2d(t)), ("/detections_3d", t, detections_3d(t))]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {topic: writer.add_connection(topic, TYPES[topic], typestore=STORE) for topic in TYPES}
        for topic, when, data in messages:
            writer.write(connections[topic], when, data)
    return path


RVIZ = """\
Visualization Manager:
  Global Options:
    Fixed Frame: map
  Displays:
    - Class: nav2_rviz_plugins/ParticleCloud
      Name: Amcl Particle Swarm
      Topic:
        Value: /particlecloud
      Shape: Arrow (3D)
      Color: 0; 180; 0
      Alpha: 1
      Min Arrow Length: 0.1
      Max Arrow Length: 0.5
      Enabled: true
    - Class: vision_msgs_rviz_plugins/Detection3DArray
      Name: Detections
      Topic:
        Value: /detections_3d
      Only Edge: true
      Line Width: 0.08
      Alpha: 0.5
      Enabled: true
    - Class: rviz_default_plugins/Image
      Name: Camera image
      Topic:
        Value: /cam/image_raw
      Enabled: true
"""
"""An RViz 2 config with nav2's and vision_msgs' display classes (their properties as RViz writes them)."""


def stack_recordings(tmp_path_factory) -> dict[str, Path]:
    """The stack bag through the real CLI, once per test run: ``plain`` (``--bag B --save``) and ``rviz`` (with
    :data:`RVIZ`); paths of the bag, the config and the two recordings."""
    import subprocess
    import sys

    from conftest import made_once

    def make(root: Path) -> None:
        bag = write_stack_bag(root / "bag")
        (root / "stack.rviz").write_text(RVIZ)
        exe = Path(sys.executable).parent / "r2d2-viz"
        for name, extra in (("plain", []), ("rviz", ["--rviz", str(root / "stack.rviz")])):
            run = subprocess.run([str(exe), "--bag", str(bag), *extra, "--save", str(root / f"{name}.rrd")],
                                 capture_output=True, text=True, timeout=120)  # fmt: skip
            (root / f"{name}.stderr").write_text(run.stderr)
            assert run.returncode == 0, run.stderr

    root = made_once(tmp_path_factory, "stack_recordings", make)
    return {
        "bag": root / "bag",
        "rviz_file": root / "stack.rviz",
        "plain": root / "plain.rrd",
        "rviz": root / "rviz.rrd",
    }
