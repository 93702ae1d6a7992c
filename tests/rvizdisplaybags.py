"""A bag for RViz 2's displays of issue 46, written by rosbags itself (its serializer and writer, independent of
r2d2_viz), with a two-joint arm, for ``tests/data/rviz/all_displays.rviz`` (one display of each of RViz 2's 32
classes; its topics are this bag's). Expected values are worked out in the tests from what is written here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from bagmaker import BagSpec, tf_message, write_bag
from msgs_build import T, cdr, header, marker_msg, pose, quat, vec

S = 1_000_000_000
T0 = 1_700_000_000 * S
URDF = """<robot name="arm">
  <link name="base_link"/><link name="arm"/><link name="wheel"/>
  <joint name="shoulder" type="revolute"><parent link="base_link"/><child link="arm"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <joint name="spin" type="continuous"><parent link="arm"/><child link="wheel"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/></joint>
</robot>
"""
EFFORTS = [(T0, [5.0, 3.0]), (T0 + S // 2, [-20.0, 1.0])]
"""(time, efforts of shoulder and spin): spin is continuous, which RViz's Effort display does not draw."""
ACCEL = ((1.0, 2.0, 3.0), (0.0, 0.0, 0.5))
SCALARS = {  # topic: (type, field, value)
    "/temperature": ("sensor_msgs/msg/Temperature", "temperature", 25.0),
    "/pressure": ("sensor_msgs/msg/FluidPressure", "fluid_pressure", 101325.0),
    "/illuminance": ("sensor_msgs/msg/Illuminance", "illuminance", 500.0),
    "/humidity": ("sensor_msgs/msg/RelativeHumidity", "relative_humidity", 0.4),
}
DEPTH_MM = np.array([[1000, 0, 2000, 1500], [500, 750, 0, 3000], [1200, 1300, 1400, 0]], dtype=np.uint16)
"""A 4 x 3 depth image (16UC1, mm; 0: no depth)."""
RGB = np.arange(4 * 3 * 3, dtype=np.uint8).reshape(3, 4, 3) * 7
P = [2.0, 0.0, 1.5, 0.0, 0.0, 2.5, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
K = [2.0, 0.0, 1.5, 0.0, 2.5, 1.0, 0.0, 0.0, 1.0]
OPTICAL = "camera_depth_optical_frame"
CAMERA_AT = (0.1, 0.0, 1.0)
IM_TIMES = (T0 + S // 10, T0 + 3 * S // 10, T0 + 6 * S // 10)
"""The interactive marker "box" appears at (1, 0, 0) in base_link, moves to (2, 0, 0), is erased."""
BOX_OFFSET = (0.0, 0.0, 0.5)
"""Its control's cube, relative to it (empty frame id)."""
TYPES = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/accel": "geometry_msgs/msg/AccelStamped",
    "/camera/depth/image_raw": "sensor_msgs/msg/Image",
    "/camera/depth/camera_info": "sensor_msgs/msg/CameraInfo",
    "/camera/color/image_raw": "sensor_msgs/msg/Image",
    "/basic_controls/update": "visualization_msgs/msg/InteractiveMarkerUpdate",
    **{topic: msgtype for topic, (msgtype, _, _) in SCALARS.items()},
}


def _stamp(t: int):
    return T("builtin_interfaces/msg/Time")(sec=t // S, nanosec=t % S)


def _header(frame: str, t: int):
    return T("std_msgs/msg/Header")(stamp=_stamp(t), frame_id=frame)


def joint_state(t: int, efforts: list[float]) -> bytes:
    msg = T("sensor_msgs/msg/JointState")(
        header=_header("", t),
        name=["shoulder", "spin"],
        position=np.array([0.2, 0.0]),
        velocity=np.zeros(0),
        effort=np.array(efforts),
    )
    return cdr(msg)


def image(t: int, frame: str, encoding: str, pixels: np.ndarray) -> bytes:
    h, w = pixels.shape[:2]
    data = np.ascontiguousarray(pixels).view(np.uint8).ravel()
    msg = T("sensor_msgs/msg/Image")(
        header=_header(frame, t), height=h, width=w, encoding=encoding, is_bigendian=0, step=len(data) // h, data=data
    )
    return cdr(msg)


def camera_info(t: int) -> bytes:
    roi = T("sensor_msgs/msg/RegionOfInterest")(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    msg = T("sensor_msgs/msg/CameraInfo")(
        header=_header(OPTICAL, t), height=3, width=4, distortion_model="plumb_bob", d=np.zeros(5),
        k=np.array(K), r=np.eye(3).ravel(), p=np.array(P), binning_x=0, binning_y=0, roi=roi,
    )  # fmt: skip
    return cdr(msg)


def _interactive(name: str, at: float) -> object:
    cube = marker_msg(1, header=header(""), pose=pose(*BOX_OFFSET), scale=vec(0.2, 0.2, 0.2))
    control = T("visualization_msgs/msg/InteractiveMarkerControl")(
        name="move_x", orientation=quat(), orientation_mode=0, interaction_mode=3, always_visible=True,
        markers=[cube], independent_marker_orientation=False, description="",
    )  # fmt: skip
    return T("visualization_msgs/msg/InteractiveMarker")(
        header=_header("base_link", IM_TIMES[0]), pose=pose(at, 0.0, 0.0), name=name, description="",
        scale=1.0, menu_entries=[], controls=[control],
    )  # fmt: skip


def im_update(markers: list, poses: list, erases: list[str], seq: int) -> bytes:
    msg = T("visualization_msgs/msg/InteractiveMarkerUpdate")(
        server_id="server", seq_num=seq, type=1, markers=markers, poses=poses, erases=erases
    )
    return cdr(msg)


def write_rviz_displays_bag(path: Path) -> Path:
    spec = BagSpec(types=dict(TYPES))
    camera = (T0, "base_link", OPTICAL, CAMERA_AT, (-0.5, 0.5, -0.5, 0.5))
    spec.add("/tf_static", T0, tf_message([camera]))
    for t, efforts in EFFORTS:
        spec.add("/joint_states", t, joint_state(t, efforts))
    linear, angular = (vec(*v) for v in ACCEL)
    accel = T("geometry_msgs/msg/Accel")(linear=linear, angular=angular)
    spec.add("/accel", T0, cdr(T("geometry_msgs/msg/AccelStamped")(header=_header("base_link", T0), accel=accel)))
    for topic, (msgtype, field, value) in SCALARS.items():
        spec.add(topic, T0, cdr(T(msgtype)(header=_header("base_link", T0), **{field: value, "variance": 0.0})))
    spec.add("/camera/depth/camera_info", T0, camera_info(T0))
    spec.add("/camera/color/image_raw", T0 + 1, image(T0 + 1, OPTICAL, "rgb8", RGB))
    spec.add("/camera/depth/image_raw", T0 + 2, image(T0 + 2, OPTICAL, "16UC1", DEPTH_MM))
    spec.add("/basic_controls/update", IM_TIMES[0], im_update([_interactive("box", 1.0)], [], [], 1))
    moved = T("visualization_msgs/msg/InteractiveMarkerPose")(
        header=_header("base_link", IM_TIMES[1]), pose=pose(2.0, 0.0, 0.0), name="box"
    )
    spec.add("/basic_controls/update", IM_TIMES[1], im_update([], [moved], [], 2))
    spec.add("/basic_controls/update", IM_TIMES[2], im_update([], [], ["box"], 3))
    spec.messages.sort(key=lambda m: m[1])
    return write_bag(path, spec)
