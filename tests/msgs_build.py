"""Build and serialise ROS 2 messages with rosbags' own typestore (independent of r2d2_viz.msgs)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

TS = get_typestore(Stores.ROS2_HUMBLE)
FOXGLOVE_VIDEO = "builtin_interfaces/Time timestamp\nstring frame_id\nuint8[] data\nstring format\n"
"""foxglove_msgs/msg/CompressedVideo.msg as Foxglove publishes it (in no distro: bags carry it)."""
TS.register(get_types_from_msg(FOXGLOVE_VIDEO, "foxglove_msgs/msg/CompressedVideo"))


def T(name: str) -> Any:
    """The rosbags class of a ROS type, e.g. ``T("sensor_msgs/msg/LaserScan")``."""
    return TS.types[name]


def cdr(msg: Any) -> bytes:
    """The message serialised as CDR (little endian), as a bag stores it."""
    return bytes(TS.serialize_cdr(msg, msg.__msgtype__))


def header(frame: str = "base_laser", sec: int = 12, nanosec: int = 345) -> Any:
    return T("std_msgs/msg/Header")(stamp=T("builtin_interfaces/msg/Time")(sec=sec, nanosec=nanosec), frame_id=frame)


def vec(x: float = 0.0, y: float = 0.0, z: float = 0.0, kind: str = "Vector3") -> Any:
    return T(f"geometry_msgs/msg/{kind}")(x=x, y=y, z=z)


def quat(x: float = 0.0, y: float = 0.0, z: float = 0.0, w: float = 1.0) -> Any:
    return T("geometry_msgs/msg/Quaternion")(x=x, y=y, z=z, w=w)


def pose(x: float = 0.0, y: float = 0.0, z: float = 0.0, q: Any = None) -> Any:
    return T("geometry_msgs/msg/Pose")(position=vec(x, y, z, "Point"), orientation=q or quat())


def color(r: float, g: float, b: float, a: float = 1.0) -> Any:
    return T("std_msgs/msg/ColorRGBA")(r=r, g=g, b=b, a=a)


def rviz_rainbow(value: float) -> tuple[int, int, int]:
    """RViz's getRainbowColor transcribed for one value (ros2/rviz intensity_pc_transformer / point_cloud_helpers),
    as 8-bit channels rounded to nearest."""
    value = min(max(value, 0.0), 1.0)
    h = value * 5.0 + 1.0
    i = math.floor(h)
    f = h - i
    if i % 2 == 0:
        f = 1 - f
    n = 1 - f
    if i <= 1:
        rgb = (n, 0.0, 1.0)
    elif i == 2:
        rgb = (0.0, n, 1.0)
    elif i == 3:
        rgb = (0.0, 1.0, n)
    elif i == 4:
        rgb = (n, 1.0, 0.0)
    else:
        rgb = (1.0, n, 0.0)
    return (round(rgb[0] * 255), round(rgb[1] * 255), round(rgb[2] * 255))


def rviz_intensity(values: list[float]) -> list[tuple[int, int, int]]:
    """RViz's Intensity transformer defaults (autocomputed bounds, rainbow, not inverted) for ``values``."""
    lo, hi = min(values), max(values)
    diff = hi - lo if hi != lo else 1e20
    return [rviz_rainbow(1.0 - (v - lo) / diff) for v in values]


def marker_msg(kind: int, **fields: Any) -> Any:
    """A ``visualization_msgs/Marker`` of type ``kind``: ADD, in odom, white, unit scale, forever, nothing extra;
    ``fields`` set the rest (rosbags' own message class)."""
    args: dict[str, Any] = {
        "header": header("odom"),
        "ns": "",
        "id": 0,
        "type": kind,
        "action": 0,
        "pose": pose(),
        "scale": vec(1.0, 1.0, 1.0),
        "color": color(1.0, 1.0, 1.0),
        "lifetime": T("builtin_interfaces/msg/Duration")(sec=0, nanosec=0),
        "frame_locked": False,
        "points": [],
        "colors": [],
        "texture_resource": "",
        "texture": T("sensor_msgs/msg/CompressedImage")(header=header(), format="", data=np.zeros(0, np.uint8)),
        "uv_coordinates": [],
        "text": "",
        "mesh_resource": "",
        "mesh_file": T("visualization_msgs/msg/MeshFile")(filename="", data=np.zeros(0, np.uint8)),
        "mesh_use_embedded_materials": False,
    }
    args.update(fields)
    return T("visualization_msgs/msg/Marker")(**args)


def duration(sec: int, nanosec: int = 0) -> Any:
    return T("builtin_interfaces/msg/Duration")(sec=sec, nanosec=nanosec)


def _marker(kind: int) -> Any:
    pts = [vec(0, 0, 0, "Point"), vec(1, 0, 0, "Point"), vec(1, 1, 0, "Point")]
    return marker_msg(
        kind,
        ns="ns",
        id=kind,
        pose=pose(1.0, 2.0, 0.0),
        scale=vec(0.2, 0.2, 0.2),
        color=color(1, 0, 0),
        points=pts if kind in (4, 5, 6, 7, 8, 11) else [],
        text="hi",
        mesh_resource="package://p/m.stl",
    )


def _rviz2_samples() -> list[Any]:
    """AccelStamped and an InteractiveMarkerUpdate with one marker of one control (issue 46's displays)."""
    accel = T("geometry_msgs/msg/Accel")(linear=vec(1, 0, 0), angular=vec(0, 0, 1))
    control = T("visualization_msgs/msg/InteractiveMarkerControl")(
        name="c", orientation=quat(), orientation_mode=0, interaction_mode=0, always_visible=True,
        markers=[marker_msg(1, header=header(""))], independent_marker_orientation=False, description="",
    )  # fmt: skip
    im = T("visualization_msgs/msg/InteractiveMarker")(
        header=header(), pose=pose(1, 0, 0), name="m", description="", scale=1.0, menu_entries=[], controls=[control]
    )
    update = T("visualization_msgs/msg/InteractiveMarkerUpdate")(
        server_id="s", seq_num=1, type=1, markers=[im], poses=[], erases=[]
    )
    return [T("geometry_msgs/msg/AccelStamped")(header=header(), accel=accel), update]


def samples() -> dict[str, bytes]:
    """One small valid message of every display type, serialised."""
    stamped = T("geometry_msgs/msg/PoseStamped")
    with_cov = T("geometry_msgs/msg/PoseWithCovariance")(pose=pose(1, 2, 3), covariance=np.eye(6).reshape(-1))
    twist = T("geometry_msgs/msg/Twist")(linear=vec(1, 0, 0), angular=vec(0, 0, 1))
    info = T("nav_msgs/msg/MapMetaData")(
        map_load_time=T("builtin_interfaces/msg/Time")(sec=0, nanosec=0),
        resolution=0.1,
        width=2,
        height=2,
        origin=pose(),
    )
    pf = T("sensor_msgs/msg/PointField")
    roi = T("sensor_msgs/msg/RegionOfInterest")(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    msgs = [
        T("sensor_msgs/msg/LaserScan")(
            header=header(),
            angle_min=0.0,
            angle_max=1.0,
            angle_increment=0.5,
            time_increment=0.0,
            scan_time=0.0,
            range_min=0.0,
            range_max=5.0,
            ranges=np.array([1, 2, 3], np.float32),
            intensities=np.array([1, 2, 3], np.float32),
        ),
        T("sensor_msgs/msg/Range")(
            header=header(), radiation_type=0, field_of_view=0.5, min_range=0.0, max_range=2.0, range=1.0
        ),
        T("sensor_msgs/msg/PointCloud2")(
            header=header(),
            height=1,
            width=2,
            fields=[pf(name=n, offset=4 * i, datatype=7, count=1) for i, n in enumerate(["x", "y", "z", "intensity"])],
            is_bigendian=False,
            point_step=16,
            row_step=32,
            data=np.arange(8, dtype=np.float32).view(np.uint8),
            is_dense=True,
        ),
        T("sensor_msgs/msg/PointCloud")(header=header(), points=[vec(1, 2, 3, "Point32")], channels=[]),
        T("sensor_msgs/msg/Image")(
            header=header(), height=1, width=2, encoding="mono8", is_bigendian=False, step=2, data=np.zeros(2, np.uint8)
        ),
        T("sensor_msgs/msg/CompressedImage")(
            header=header(), format="png", data=np.frombuffer(b"\x89PNG\r\n\x1a\nxxxx", np.uint8)
        ),
        T("foxglove_msgs/msg/CompressedVideo")(  # an H.264 SPS and IDR slice (Annex B), a keyframe
            timestamp=T("builtin_interfaces/msg/Time")(sec=12, nanosec=345),
            frame_id="camera",
            data=np.frombuffer(b"\x00\x00\x00\x01\x67\x42\x00\x0a\x00\x00\x00\x01\x65\x88\x84", np.uint8),
            format="h264",
        ),
        T("sensor_msgs/msg/CameraInfo")(
            header=header(),
            height=480,
            width=640,
            distortion_model="",
            d=np.zeros(0),
            k=np.array([500.0, 0, 320, 0, 500, 240, 0, 0, 1]),
            r=np.eye(3).reshape(-1),
            p=np.zeros(12),
            binning_x=0,
            binning_y=0,
            roi=roi,
        ),
        _marker(2),
        T("visualization_msgs/msg/MarkerArray")(markers=[_marker(k) for k in range(12)]),
        T("nav_msgs/msg/Path")(header=header(), poses=[stamped(header=header(), pose=pose(i, 0, 0)) for i in range(3)]),
        T("nav_msgs/msg/Odometry")(
            header=header(),
            child_frame_id="base",
            pose=with_cov,
            twist=T("geometry_msgs/msg/TwistWithCovariance")(twist=twist, covariance=np.zeros(36)),
        ),
        T("nav_msgs/msg/OccupancyGrid")(header=header(), info=info, data=np.array([0, 100, -1, 50], np.int8)),
        T("nav_msgs/msg/GridCells")(header=header(), cell_width=0.1, cell_height=0.1, cells=[vec(1, 1, 0, "Point")]),
        stamped(header=header(), pose=pose(1, 2, 3)),
        T("geometry_msgs/msg/PoseArray")(header=header(), poses=[pose(), pose(1, 0, 0)]),
        T("geometry_msgs/msg/PoseWithCovarianceStamped")(header=header(), pose=with_cov),
        T("geometry_msgs/msg/PointStamped")(header=header(), point=vec(1, 2, 3, "Point")),
        T("geometry_msgs/msg/PolygonStamped")(
            header=header(),
            polygon=T("geometry_msgs/msg/Polygon")(points=[vec(0, 0, 0, "Point32"), vec(1, 0, 0, "Point32")]),
        ),
        T("geometry_msgs/msg/WrenchStamped")(
            header=header(), wrench=T("geometry_msgs/msg/Wrench")(force=vec(1, 0, 0), torque=vec(0, 0, 1))
        ),
        T("geometry_msgs/msg/TwistStamped")(header=header(), twist=twist),
        *_rviz2_samples(),
    ]
    msgs += _telemetry_samples()
    out = {m.__msgtype__: cdr(m) for m in msgs}
    out["rosgraph_msgs/msg/Log"] = _ros1_log()
    from stackbags import T0, detections_2d, detections_3d, particle_cloud, voxel_grid  # the upstream .msg files'

    out["nav2_msgs/msg/ParticleCloud"], out["nav2_msgs/msg/VoxelGrid"] = particle_cloud(T0), voxel_grid(T0)
    out["vision_msgs/msg/Detection2DArray"], out["vision_msgs/msg/Detection3DArray"] = (
        detections_2d(T0),
        detections_3d(T0),
    )
    return out


ROS1_LOG_AS_CDR = "std_msgs/Header header\nbyte level\nstring name\nstring msg\nstring file\nstring function\n"
"""ROS 1's rosgraph_msgs/Log once a ROS 1 bag's message is converted to CDR (rosbags' ros1_to_cdr with ROS 2's
header, which has no ``seq``)."""


def _ros1_log() -> bytes:
    from rosbags.typesys import get_types_from_msg

    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg(ROS1_LOG_AS_CDR + "uint32 line\nstring[] topics\n", "rosgraph_msgs/msg/Log"))
    msg = store.types["rosgraph_msgs/msg/Log"](header(), 4, "node", "text", "f.cpp", "fn", 3, ["/a"])
    return bytes(store.serialize_cdr(msg, "rosgraph_msgs/msg/Log"))


def _telemetry_samples() -> list[Any]:
    """The log, diagnostics, sensors and numbers (:mod:`r2d2_viz.msgs.telemetry`)."""
    stamp = T("builtin_interfaces/msg/Time")(sec=1, nanosec=2)
    kv = T("diagnostic_msgs/msg/KeyValue")(key="v", value="1.5")
    status = T("diagnostic_msgs/msg/DiagnosticStatus")(level=1, name="a/b", message="m", hardware_id="h", values=[kv])
    cov = np.zeros(9)
    msgs = [
        T("rcl_interfaces/msg/Log")(stamp=stamp, level=30, name="n", msg="m", file="f", function="g", line=1),
        T("diagnostic_msgs/msg/DiagnosticArray")(header=header(), status=[status]),
        T("std_msgs/msg/String")(data="hello"),
        T("sensor_msgs/msg/Imu")(header(), quat(), cov, vec(1, 2, 3), cov, vec(0, 0, 9.8), cov),
        T("sensor_msgs/msg/NavSatFix")(
            header(), T("sensor_msgs/msg/NavSatStatus")(status=0, service=1), 48.0, 2.0, 30.0, cov, 0
        ),
        T("sensor_msgs/msg/BatteryState")(
            header(),
            12.0,
            20.0,
            -1.0,
            5.0,
            10.0,
            10.0,
            0.5,
            2,
            1,
            2,
            True,
            np.zeros(0, np.float32),
            np.zeros(0, np.float32),
            "base",
            "SN",
        ),
        T("sensor_msgs/msg/Temperature")(header=header(), temperature=21.5, variance=0.0),
        T("sensor_msgs/msg/FluidPressure")(header=header(), fluid_pressure=101325.0, variance=0.0),
        T("sensor_msgs/msg/RelativeHumidity")(header=header(), relative_humidity=0.4, variance=0.0),
        T("sensor_msgs/msg/Illuminance")(header=header(), illuminance=300.0, variance=0.0),
        T("std_msgs/msg/Bool")(data=True),
    ]
    for kind, value in (("Float32", 1.5), ("Float64", 2.5)):
        msgs.append(T(f"std_msgs/msg/{kind}")(data=value))
    for bits in (8, 16, 32, 64):
        msgs += [T(f"std_msgs/msg/Int{bits}")(data=-3), T(f"std_msgs/msg/UInt{bits}")(data=3)]
    return msgs
