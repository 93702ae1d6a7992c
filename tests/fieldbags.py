"""Bags of topics no display draws, for the generic field decoding (:mod:`r2d2_viz.msgs.generic.fields`): a lab's own
``my_msgs/msg/Battery`` (its definition only in the bag), a controller's state shaped like ROS 2's
``control_msgs/msg/JointTrajectoryControllerState``, and odometry — written by rosbags (its serializer, its writer,
types registered from .msg text), so that rosbags' deserializer is the golden source of every field."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from r2d2_viz.msgs.generic.fields import MAX_ITEMS, MAX_NESTED

BATTERY = "my_msgs/msg/Battery"
BATTERY_MSG = """std_msgs/Header header
float32 voltage
float32[3] cell_temperatures
uint8 status
string chemistry
bool charging
int64[] events
my_msgs/Cell[] cells
uint8[] blob
"""
CELL = "my_msgs/msg/Cell"
CELL_MSG = "string name\nfloat64 charge\n"
STATE = "control_msgs/msg/JointTrajectoryControllerState"
STATE_MSG = """std_msgs/Header header
string[] joint_names
trajectory_msgs/JointTrajectoryPoint reference
trajectory_msgs/JointTrajectoryPoint feedback
trajectory_msgs/JointTrajectoryPoint error
trajectory_msgs/JointTrajectoryPoint output
trajectory_msgs/JointTrajectoryPoint desired
trajectory_msgs/JointTrajectoryPoint actual
string[] multi_dof_joint_names
"""
TYPES = {"/battery": BATTERY, "/arm_controller/state": STATE, "/odom": "nav_msgs/msg/Odometry"}
T0 = 1_700_000_000_000_000_000
JOINTS = ("panda_joint1", "panda_joint2", "panda_joint3")


def store():  # type: ignore[no-untyped-def]
    ts = get_typestore(Stores.ROS2_HUMBLE)
    types = get_types_from_msg(CELL_MSG, CELL)
    types |= get_types_from_msg(BATTERY_MSG, BATTERY)
    if STATE not in ts.fielddefs:
        types |= get_types_from_msg(STATE_MSG, STATE)
    ts.register(types)
    return ts


def messages(n: int, rate: float = 100.0) -> list[tuple[str, int, bytes]]:
    """``n`` messages on each topic at ``rate`` Hz: (topic, receive ns, CDR)."""
    ts = store()
    T = ts.types
    out = []
    for k in range(n):
        t = T0 + int(k * 1e9 / rate)
        header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(t, 1_000_000_000)), "base_link")
        cells = [T[CELL](f"cell{i}" + "x" * (k % 3), 0.5 + 0.01 * i + k) for i in range(k % 4)]
        battery = T[BATTERY](
            header,
            12.0 + 0.01 * k,
            np.array([20.0, 21.0, 22.0 + k], dtype=np.float32),
            k % 5,
            "LiPo" if k % 2 else "LiFePO4",
            bool(k % 2),
            np.arange(k % 3, dtype=np.int64) * 7,
            cells,
            np.arange(k % 300, dtype=np.uint8),
        )
        out.append(("/battery", t, bytes(ts.serialize_cdr(battery, BATTERY))))
        fields = {"header": header, "joint_names": list(JOINTS), "multi_dof_joint_names": []}
        for name, scale in (("reference", 1.0), ("feedback", 0.9), ("error", 0.1), ("output", 2.0)):
            fields[name] = _point(T, scale, k)
        for name, scale in (("desired", 1.0), ("actual", 0.9)):
            fields[name] = _point(T, scale, k)
        names = [f for f, _ in ts.fielddefs[STATE][1]]
        state = T[STATE](*(fields[f] for f in names))
        out.append(("/arm_controller/state", t + 1, bytes(ts.serialize_cdr(state, STATE))))
        pose = T["geometry_msgs/msg/Pose"](
            T["geometry_msgs/msg/Point"](0.01 * k, 0.0, 0.0), T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0)
        )
        twist = T["geometry_msgs/msg/Twist"](
            T["geometry_msgs/msg/Vector3"](1.0 + np.sin(k / 10), 0.0, 0.0), T["geometry_msgs/msg/Vector3"](0, 0, 0.2)
        )
        odom = T["nav_msgs/msg/Odometry"](
            header,
            "base_link",
            T["geometry_msgs/msg/PoseWithCovariance"](pose, np.zeros(36)),
            T["geometry_msgs/msg/TwistWithCovariance"](twist, np.eye(6).ravel() * k),
        )
        out.append(("/odom", t + 2, bytes(ts.serialize_cdr(odom, "nav_msgs/msg/Odometry"))))
    return out


def _point(T: dict, scale: float, k: int) -> object:  # type: ignore[type-arg]
    x = np.array([scale * k, -scale * k, 0.5 * scale], dtype=np.float64)
    duration = T["builtin_interfaces/msg/Duration"](0, 0)
    return T["trajectory_msgs/msg/JointTrajectoryPoint"](x, x * 0.1, np.zeros(0), np.zeros(0), duration)


def write(path: Path, msgs: list[tuple[str, int, bytes]], *, storage: str = "mcap") -> Path:
    """A rosbag2 directory of ``msgs``; the types' definitions go into the bag (MCAP schemas, db3 table)."""
    ts = store()
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connections = {}
        for topic, t, data in msgs:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, TYPES[topic], typestore=ts)
            writer.write(connections[topic], t, data)
    return path


def expected_fields(ts: Any, msg: Any, msgtype: str, prefix: str = "") -> dict[str, Any]:
    """``ros2 topic echo``'s names and values of a rosbags message, summarised as the README says (independent of
    the walk under test: rosbags' dataclasses and field definitions)."""
    out: dict[str, Any] = {}
    for name, desc in ts.fielddefs[msgtype][1]:
        value, path = getattr(msg, name), prefix + name
        kind, rest = desc
        if kind == 2:
            out |= expected_fields(ts, value, rest, path + ".")
        elif kind == 1:
            out[path] = value
        else:
            sub = rest[0]
            if sub[0] == 1 and sub[1][0] != "string":
                array = np.asarray(value)
                if len(array) > MAX_ITEMS or (kind == 4 and array.dtype.itemsize == 1 and array.dtype != bool):
                    out[f"{path}.len"] = len(array)
                    if len(array):
                        out[f"{path}.min"], out[f"{path}.max"] = array.min(), array.max()
                    continue
                out |= {f"{path}[{i}]": v for i, v in enumerate(array)}
            elif len(value) > MAX_NESTED:
                out[f"{path}.len"] = len(value)
            else:
                for i, item in enumerate(value):
                    if sub[0] == 1:
                        out[f"{path}[{i}]"] = item
                    else:
                        out |= expected_fields(ts, item, sub[1], f"{path}[{i}].")
    return out
