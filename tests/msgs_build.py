"""Build and serialise ROS 2 messages with rosbags' own typestore (independent of r2d2_viz.msgs)."""

from __future__ import annotations

import math
from typing import Any

from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_HUMBLE)


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
