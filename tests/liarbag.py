"""A bag whose display messages lie, written by rosbags itself: markers with NaN, infinite and huge (1e300)
scales, positions and colours, all-zero quaternions; a PointCloud2 and an Image whose sizes do not match their
data; a map whose cells are 3e38 m wide. Nothing here is drawable as sent: the app must warn (grouped), not
crash, and leak nothing from inside its libraries (numpy's ``RuntimeWarning: overflow encountered in cast`` among
them)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from bagmaker import BagSpec, tf_message, write_bag
from msgs_build import T, cdr, color, header, marker_msg, pose, quat, vec

S = 1_000_000_000
T0 = 1_700_000_000 * S
HUGE = 1e300  # finite as a double, infinite as a float32
TYPES = {
    "/markers": "visualization_msgs/msg/MarkerArray",
    "/cloud": "sensor_msgs/msg/PointCloud2",
    "/image": "sensor_msgs/msg/Image",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/map": "nav_msgs/msg/OccupancyGrid",
}


def _liars() -> list[object]:
    """Each lie alone in a marker (a lying pose, scale, colour or point), for cubes to texts."""
    markers = []
    for key, value in enumerate((float("nan"), float("inf"), -float("inf"), HUGE, -HUGE)):
        f32 = value if abs(value) != HUGE else float("nan")  # ColorRGBA is float32: 1e300 cannot even be written
        for kind in (1, 2, 3, 0, 4, 8, 9):  # cube, sphere, cylinder, arrow, line strip, points, text
            points = [vec(0, 0, 0, "Point"), vec(value, 1, 0, "Point"), vec(1, 1, 0, "Point")]
            base = {"ns": f"liar{kind}", "text": "lie", "points": [*points[:1], *points[2:]] if kind in (4, 8) else []}
            lies = (
                {"pose": pose(value, 0.0, 0.0, quat(0, 0, 0, 0))},
                {"pose": pose(0.0, 0.0, 0.0, quat(0, 0, 0, 0)), "scale": vec(value, value, value)},
                {"color": color(f32, 0.5, 0.5, 1.0)},
                {"points": points if kind in (4, 8) else []},
            )
            markers.extend(marker_msg(kind, id=10 * key + k, **{**base, **lie}) for k, lie in enumerate(lies))
    return markers


def _cloud(sec: int) -> bytes:
    field = T("sensor_msgs/msg/PointField")
    fields = [field(name=n, offset=4 * k, datatype=7, count=1) for k, n in enumerate("xyz")]
    data = np.frombuffer(np.array([[np.inf, 1, 2]] * 3, np.float32).tobytes(), np.uint8)
    return cdr(
        T("sensor_msgs/msg/PointCloud2")(
            header=header("odom", sec, 0),
            height=1,
            width=1000,  # says 1000 points, carries 3 (one of them infinite)
            fields=fields,
            is_bigendian=False,
            point_step=12,
            row_step=12000,
            data=data,
            is_dense=True,
        )
    )


def _image(sec: int) -> bytes:
    return cdr(
        T("sensor_msgs/msg/Image")(
            header=header("odom", sec, 0),
            height=480,
            width=640,  # says 640×480 rgb8, carries 10 bytes
            encoding="rgb8",
            is_bigendian=0,
            step=1920,
            data=np.zeros(10, np.uint8),
        )
    )


def _map() -> bytes:
    """A 2 x 2 map whose cells say they are 3e38 m wide (resolution is a float32: 3e38 fits, 6e38 would not): its
    far corner, 6e38 m away, is infinite as a float32 (issue 29: the view fit handed it to Rerun's converters)."""
    info = T("nav_msgs/msg/MapMetaData")(
        map_load_time=T("builtin_interfaces/msg/Time")(sec=0, nanosec=0),
        resolution=3e38,
        width=2,
        height=2,
        origin=pose(0.0, 0.0, 0.0),
    )
    return cdr(T("nav_msgs/msg/OccupancyGrid")(header=header("odom"), info=info, data=np.zeros(4, np.int8)))


def write_liar_bag(path: Path) -> Path:
    spec = BagSpec(types=TYPES)
    for k in range(3):
        t = T0 + k * S
        spec.add("/tf", t, tf_message([(t, "odom", "base_link", (HUGE, 0.0, 0.0), (0, 0, 0, 0))]))
        for n, liar in enumerate(_liars()):  # one a message: a NaN one must not hide a huge one
            spec.add("/markers", t + 10 + n, cdr(T("visualization_msgs/msg/MarkerArray")(markers=[liar])))
        spec.add("/cloud", t + 2, _cloud(int(t // S)))
        spec.add("/image", t + 3, _image(int(t // S)))
        spec.add("/map", t + 4, _map())
    return write_bag(path, spec)
