"""Bags of the robot's log, its diagnostics and sensors no RViz display draws, written by rosbags itself (its own
serializers and writers, ROS 2 MCAP and ROS 1 alike), with a TF tree so the replay has a fixed frame. Every
expected value below is worked out by hand from what is written here."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

S = 1_000_000_000
T0 = 1_700_000_000 * S
HUMBLE = get_typestore(Stores.ROS2_HUMBLE)
NOETIC = get_typestore(Stores.ROS1_NOETIC)
NOETIC.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))

LOG = [  # (receive time, ROS 2 level, ROS 1 level, node, text, file, function, line, Rerun's level)
    (T0 + 1 * S // 10, 10, 1, "planner", "tick", "plan.cpp", "step", 7, "DEBUG"),
    (T0 + 2 * S // 10, 20, 2, "driver", "motors on", "drv.cpp", "start", 42, "INFO"),
    (T0 + 3 * S // 10, 30, 4, "driver", "current high", "drv.cpp", "check", 88, "WARN"),
    (T0 + 4 * S // 10, 40, 8, "driver", "overcurrent", "drv.cpp", "check", 91, "ERROR"),
    (T0 + 5 * S // 10, 50, 16, "safety", "e-stop", "safety.py", "trip", 3, "CRITICAL"),
]
"""rqt_console's line, by hand: ``[node] text (file:function:line)``."""
DIAG = [  # (receive time, [(name, level, message, key/values)])
    (T0 + 1 * S, [("motor: left", 0, "running", [("current", "1.5"), ("mode", "auto")]), ("/Robot/Power", 0, "", [])]),
    (T0 + 2 * S, [("motor: left", 1, "hot", [("current", "4.25"), ("mode", "auto")]), ("/Robot/Power", 3, "", [])]),
    (T0 + 3 * S, [("motor: left", 2, "stalled", [("current", "n/a"), ("mode", "off")])]),
]
DIAG_ENTITIES = {"motor: left": "/diagnostics/motor_left", "/Robot/Power": "/diagnostics/Robot/Power"}
"""Each status's entity: its name split at '/', a part's other characters than letters, digits, _ - . as one _."""
DIAG_STATES = {
    "motor: left": ["OK: running", "WARN: hot", "ERROR: stalled"],
    "/Robot/Power": ["OK", "STALE"],
}
IMU_TIME = T0 + 15 * S // 10
IMU_Q = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))  # 90° about z: x → y, y → -x
IMU_AXES = [[0.0, 0.3, 0.0], [-0.3, 0.0, 0.0], [0.0, 0.0, 0.3]]
IMU_RATES = [0.1, -0.2, 0.3]
IMU_ACCEL = [0.0, 0.5, 9.81]
FIX_TIME = T0 + 16 * S // 10
FIX = (48.8584, 2.2945, 35.0)
BATTERY_TIME = T0 + 17 * S // 10
BATTERY = {"voltage": 24.5, "current": -3.0, "charge": 10.0, "percentage": 0.8, "temperature": 31.0}
NUMBERS = [(T0 + k * S // 4, 0.5 * k) for k in range(4)]  # /speed (Float64)
FLAG = [(T0 + S // 4, True), (T0 + S // 2, False)]  # /flag (Bool) → 1, 0
STRING_TIME, STRING = T0 + 18 * S // 10, "docked"


def _time(store: Any, t_ns: int) -> Any:
    return store.types["builtin_interfaces/msg/Time"](*divmod(t_ns, S))


def _diagnostics(store: Any, header: Any, statuses: list) -> Any:
    T = store.types
    kv, status = T["diagnostic_msgs/msg/KeyValue"], T["diagnostic_msgs/msg/DiagnosticStatus"]
    items = [status(lv, n, m, "hw0", [kv(k, v) for k, v in vs]) for n, lv, m, vs in statuses]
    return T["diagnostic_msgs/msg/DiagnosticArray"](header, items)


def _tf(store: Any, header: Any) -> Any:
    """odom → imu_link, 1 m ahead: the replay's fixed frame is odom."""
    T = store.types
    v, q = T["geometry_msgs/msg/Vector3"](1.0, 0.0, 0.0), T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0)
    tr = T["geometry_msgs/msg/Transform"](v, q)
    return T["tf2_msgs/msg/TFMessage"]([T["geometry_msgs/msg/TransformStamped"](header, "imu_link", tr)])


def _ros2(store: Any) -> dict[str, list[tuple[int, Any]]]:
    T = store.types

    def header(t_ns: int, frame: str = "") -> Any:
        return T["std_msgs/msg/Header"](_time(store, t_ns), frame)

    log = T["rcl_interfaces/msg/Log"]
    out: dict[str, list[tuple[int, Any]]] = {}
    out["/tf_static"] = [(T0, _tf(store, header(T0, "odom")))]
    out["/rosout"] = [
        (t, log(_time(store, t), lv, node, text, f, fn, ln)) for t, lv, _, node, text, f, fn, ln, _ in LOG
    ]
    out["/diagnostics"] = [(t, _diagnostics(store, header(t), s)) for t, s in DIAG]
    out["/imu"] = [(IMU_TIME, _imu(T, header(IMU_TIME, "imu_link")))]
    status = T["sensor_msgs/msg/NavSatStatus"](0, 1)
    out["/fix"] = [(FIX_TIME, T["sensor_msgs/msg/NavSatFix"](header(FIX_TIME, "gps"), status, *FIX, np.zeros(9), 0))]
    out["/battery"] = [(BATTERY_TIME, _battery(T, header(BATTERY_TIME)))]
    out["/speed"] = [(t, T["std_msgs/msg/Float64"](v)) for t, v in NUMBERS]
    out["/flag"] = [(t, T["std_msgs/msg/Bool"](v)) for t, v in FLAG]
    out["/status"] = [(STRING_TIME, T["std_msgs/msg/String"](STRING))]
    return out


def _imu(T: Any, header: Any) -> Any:
    v3 = T["geometry_msgs/msg/Vector3"]
    q = T["geometry_msgs/msg/Quaternion"](*IMU_Q)
    return T["sensor_msgs/msg/Imu"](header, q, np.zeros(9), v3(*IMU_RATES), np.zeros(9), v3(*IMU_ACCEL), np.zeros(9))


def _battery(T: Any, header: Any) -> Any:
    b, cells = BATTERY, np.zeros(0, np.float32)
    values = (b["voltage"], b["temperature"], b["current"], b["charge"], 20.0, 20.0, b["percentage"])
    return T["sensor_msgs/msg/BatteryState"](header, *values, 2, 1, 2, True, cells, cells, "base", "SN1")


TYPES = {
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/rosout": "rcl_interfaces/msg/Log",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    "/imu": "sensor_msgs/msg/Imu",
    "/fix": "sensor_msgs/msg/NavSatFix",
    "/battery": "sensor_msgs/msg/BatteryState",
    "/speed": "std_msgs/msg/Float64",
    "/flag": "std_msgs/msg/Bool",
    "/status": "std_msgs/msg/String",
}


def write_telemetry_bag(path: Path) -> Path:
    """A ROS 2 MCAP bag (a folder) of every topic of :data:`TYPES`."""
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        for topic, rows in _ros2(HUMBLE).items():
            c = writer.add_connection(topic, TYPES[topic], typestore=HUMBLE)
            for t, msg in rows:
                writer.write(c, t, bytes(HUMBLE.serialize_cdr(msg, TYPES[topic])))
    return path


def write_ros1_telemetry_bag(path: Path) -> Path:
    """The same as a ROS 1 bag (Noetic's types): ``rosgraph_msgs/Log`` with ROS 1's levels (1, 2, 4, 8, 16), its
    header with a ``seq``; /tf_static, /diagnostics, /imu and /speed."""
    T = NOETIC.types

    def header(t_ns: int, frame: str = "") -> Any:
        return T["std_msgs/msg/Header"](0, _time(NOETIC, t_ns), frame)

    log = T["rosgraph_msgs/msg/Log"]
    rows: dict[str, tuple[str, list[tuple[int, Any]]]] = {
        "/tf_static": (TYPES["/tf_static"], [(T0, _tf(NOETIC, header(T0, "odom")))]),
        "/rosout": (
            "rosgraph_msgs/msg/Log",
            [(t, log(header(t), lv, node, text, f, fn, ln, [])) for t, _, lv, node, text, f, fn, ln, _ in LOG],
        ),
        "/diagnostics": (TYPES["/diagnostics"], [(t, _diagnostics(NOETIC, header(t), s)) for t, s in DIAG]),
        "/imu": (TYPES["/imu"], [(IMU_TIME, _imu(T, header(IMU_TIME, "imu_link")))]),
        "/speed": (TYPES["/speed"], [(t, T["std_msgs/msg/Float64"](v)) for t, v in NUMBERS]),
    }
    with Ros1Writer(path) as writer:
        for topic, (msgtype, msgs) in rows.items():
            c = writer.add_connection(topic, msgtype, typestore=NOETIC, latching=int(topic == "/tf_static"))
            for t, msg in msgs:
                writer.write(c, t, NOETIC.serialize_ros1(msg, msgtype))
    return path
