"""A bag of RViz display topics, written by rosbags itself (its serializer and writer, independent of r2d2_viz):
a laser in ``base_laser`` 0.5 m ahead of ``base_link``, moving along x in ``odom``; its scans, a MarkerArray
(a cube kept 1 s, a sphere deleted later), a map, odometry, a scan with an empty frame id and one garbage message.
Every expected value below is worked out by hand from what is written here."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from bagmaker import BagSpec, tf_message, write_bag
from msgs_build import T, cdr, color, duration, header, marker_msg, pose, quat, vec

S = 1_000_000_000
T0 = 1_700_000_000 * S
TYPES = {
    "/scan": "sensor_msgs/msg/LaserScan",
    "/markers": "visualization_msgs/msg/MarkerArray",
    "/map": "nav_msgs/msg/OccupancyGrid",
    "/odom": "nav_msgs/msg/Odometry",
    "/chatter": "std_msgs/msg/ColorRGBA",  # a type no display draws
}
SCAN_TIMES = [T0 + k * S // 10 for k in range(20)]  # 10 Hz for 2 s
RANGES = [1.0, 2.0, float("nan"), 50.0]  # beams at 0°, 90°, 180°, 270°: NaN and 50 m (> range_max 10) dropped
SCAN_POINTS = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]]  # (r cos a, r sin a, 0) of the two valid beams, in base_laser
MARKER_TIME = T0 + 5 * S // 10
CUBE_LIFETIME_S = 1
SPHERE_DELETED = T0 + 15 * S // 10
MAP_TIME = T0 + S // 10
EMPTY_FRAME_TIME = T0 + 3 * S // 10
GARBAGE_TIME = T0 + 7 * S // 10


def laser_scan(sec: int, nanosec: int, frame: str = "base_laser") -> bytes:
    return cdr(
        T("sensor_msgs/msg/LaserScan")(
            header=header(frame, sec, nanosec),
            angle_min=0.0,
            angle_max=1.5 * math.pi,
            angle_increment=math.pi / 2,
            time_increment=0.0,
            scan_time=0.1,
            range_min=0.1,
            range_max=10.0,
            ranges=np.array(RANGES, dtype=np.float32),
            intensities=np.zeros(0, np.float32),
        )
    )


def marker(kind: int, action: int, ns: str, key: int, *, lifetime_s: int = 0, at: tuple[float, float] = (0, 0)):
    return marker_msg(
        kind,
        action=action,
        ns=ns,
        id=key,
        pose=pose(at[0], at[1], 0.0, quat(0, 0, 0, 1)),
        scale=vec(0.4, 0.4, 0.4),
        color=color(0.0, 0.0, 1.0),
        lifetime=duration(lifetime_s),
    )


def marker_array(*markers: object) -> bytes:
    return cdr(T("visualization_msgs/msg/MarkerArray")(markers=list(markers)))


def occupancy_grid() -> bytes:
    info = T("nav_msgs/msg/MapMetaData")(
        map_load_time=T("builtin_interfaces/msg/Time")(sec=0, nanosec=0),
        resolution=0.5,
        width=4,
        height=2,
        origin=pose(-1.0, -0.5, 0.0),
    )
    cells = np.array([0, 100, -1, 50, 0, 0, 100, 100], dtype=np.int8)
    return cdr(T("nav_msgs/msg/OccupancyGrid")(header=header("odom"), info=info, data=cells))


def odometry(sec: int, x: float) -> bytes:
    cov = np.zeros(36)
    return cdr(
        T("nav_msgs/msg/Odometry")(
            header=header("odom", sec, 0),
            child_frame_id="base_link",
            pose=T("geometry_msgs/msg/PoseWithCovariance")(pose=pose(x, 0.0, 0.0), covariance=cov),
            twist=T("geometry_msgs/msg/TwistWithCovariance")(
                twist=T("geometry_msgs/msg/Twist")(linear=vec(), angular=vec()), covariance=cov
            ),
        )
    )


def base_x(t_ns: int) -> float:
    """Where base_link is along odom's x at a time: 0.5 m/s from T0."""
    return 0.5 * (t_ns - T0) / S


def write_display_bag(path: Path, *, storage: str = "mcap") -> Path:
    spec = BagSpec(types={**TYPES, "/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage"})
    spec.add("/tf_static", T0, tf_message([(T0, "base_link", "base_laser", (0.5, 0.0, 0.0), (0, 0, 0, 1))]))
    for k in range(21):
        t = T0 + k * S // 10
        spec.add("/tf", t, tf_message([(t, "odom", "base_link", (base_x(t), 0.0, 0.0), (0, 0, 0, 1))]))
    for t in SCAN_TIMES:
        sec, nanosec = divmod(t, S)
        spec.add("/scan", t, laser_scan(sec, nanosec, "/base_laser" if t == SCAN_TIMES[1] else "base_laser"))
    spec.add("/scan", EMPTY_FRAME_TIME + 1, laser_scan(*divmod(EMPTY_FRAME_TIME, S), frame=""))
    spec.add("/scan", GARBAGE_TIME + 1, b"\x00\x01\x00\x00garbage")
    spec.add("/map", MAP_TIME, occupancy_grid())
    cube = marker(1, 0, "boxes", 1, lifetime_s=CUBE_LIFETIME_S, at=(1.0, 1.0))
    spec.add("/markers", MARKER_TIME, marker_array(cube, marker(2, 0, "balls", 7, at=(2.0, -1.0))))
    spec.add("/markers", SPHERE_DELETED, marker_array(marker(2, 2, "balls", 7)))
    for k in range(3):
        spec.add("/odom", T0 + k * S, odometry(int(T0 // S) + k, float(k)))
    spec.add("/chatter", T0, cdr(color(1.0, 0.5, 0.0)))
    spec.messages.sort(key=lambda m: m[1])
    return write_bag(path, spec, storage=storage)
