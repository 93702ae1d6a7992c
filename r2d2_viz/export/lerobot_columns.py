"""A bag's topics as a dataset's columns: joint positions (``observation.state``) and a command (``action``) as
named values over time, and frames sampled from them at ``fps``: each frame takes, per name, the latest value at or
before its time (ROS's ``message_filters`` "latest" policy), and the episode starts once every name has had one.

Commands: ``sensor_msgs/JointState`` (positions), ``trajectory_msgs/JointTrajectory`` (its first point's
positions), ``geometry_msgs/Twist`` and ``TwistStamped`` (linear then angular x y z) and
``std_msgs/Float64MultiArray`` (its data, one name per element). Pure: numpy and the message decoders.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import I64
from r2d2_viz.msgs.typestore import MsgError, deserialize

ACTION_TYPES = (
    "sensor_msgs/msg/JointState",
    "trajectory_msgs/msg/JointTrajectory",
    "geometry_msgs/msg/Twist",
    "geometry_msgs/msg/TwistStamped",
    "std_msgs/msg/Float64MultiArray",
)
TWIST_NAMES = ("linear.x", "linear.y", "linear.z", "angular.x", "angular.y", "angular.z")


@dataclass
class Series:
    """Named values over time (ns); names in first-seen order."""

    times: dict[str, list[int]] = field(default_factory=dict)
    values: dict[str, list[float]] = field(default_factory=dict)

    def add(self, time_ns: int, names: Sequence[str], values: Iterable[float]) -> None:
        for name, value in zip(names, values, strict=False):
            self.times.setdefault(name, []).append(time_ns)
            self.values.setdefault(name, []).append(float(value))

    @property
    def names(self) -> list[str]:
        return list(self.times)

    def first_ns(self) -> int:
        return max(min(t) for t in self.times.values())

    def last_ns(self) -> int:
        return min(max(t) for t in self.times.values())

    def at(self, frames_ns: I64, names: Sequence[str]) -> npt.NDArray[np.float32]:
        """``(n, len(names))`` float32: each name's latest value at or before each frame time."""
        out = np.empty((len(frames_ns), len(names)), dtype=np.float32)
        for k, name in enumerate(names):
            times = np.asarray(self.times[name], dtype=np.int64)
            values = np.asarray(self.values[name], dtype=np.float64)
            order = np.argsort(times, kind="stable")  # header stamps may go back; receive times never do
            held = np.searchsorted(times[order], frames_ns, side="right") - 1
            out[:, k] = values[order][np.maximum(held, 0)]
        return out


def stamp_ns(msg: Any, receive_ns: int, header: bool) -> int:
    """The message's time: its header stamp with ``--time header`` (where it has a header), else its receive time."""
    if header and hasattr(msg, "header"):
        return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
    return receive_ns


def add_message(series: Series, msgtype: str, data: bytes | memoryview, receive_ns: int, header: bool) -> None:
    """Decode one message of ``msgtype`` into ``series`` (a MsgError when it cannot be decoded)."""
    msg = deserialize(data, msgtype)
    time_ns = stamp_ns(msg, receive_ns, header)
    if msgtype == "sensor_msgs/msg/JointState":
        if len(msg.position) != len(msg.name):
            raise MsgError(f"{len(msg.name)} names but {len(msg.position)} positions")
        series.add(time_ns, [str(n) for n in msg.name], msg.position)
    elif msgtype == "trajectory_msgs/msg/JointTrajectory":
        if len(msg.points):
            positions = msg.points[0].positions
            if len(positions) != len(msg.joint_names):
                raise MsgError(f"{len(msg.joint_names)} joint names but {len(positions)} positions")
            series.add(time_ns, [str(n) for n in msg.joint_names], positions)
    elif msgtype in ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"):
        twist = msg.twist if msgtype.endswith("Stamped") else msg
        lin, ang = twist.linear, twist.angular
        series.add(time_ns, TWIST_NAMES, (lin.x, lin.y, lin.z, ang.x, ang.y, ang.z))
    elif msgtype == "std_msgs/msg/Float64MultiArray":
        data_ = np.asarray(msg.data, dtype=np.float64)
        if series.times and len(data_) != len(series.times):
            raise MsgError(f"{len(data_)} values where earlier messages had {len(series.times)}")
        series.add(time_ns, [f"data[{i}]" for i in range(len(data_))], data_)
    else:
        raise MsgError(f"{msgtype} is not a command type ({', '.join(t.rsplit('/', 1)[1] for t in ACTION_TYPES)})")


def ordered(names: Sequence[str], robot_order: Sequence[str]) -> list[str]:
    """``names`` in the robot's joint order (those it has), then the others as first seen."""
    place = {name: k for k, name in enumerate(robot_order)}
    known = sorted((n for n in names if n in place), key=place.__getitem__)
    return known + [n for n in names if n not in place]


def frame_times(first_ns: int, last_ns: int, fps: int) -> I64:
    """Frame times from ``first_ns`` every ``1/fps`` up to ``last_ns`` (both included), in ns."""
    if last_ns < first_ns:
        return np.zeros(0, dtype=np.int64)
    count = (last_ns - first_ns) * fps // 1_000_000_000 + 1
    return first_ns + (np.arange(count, dtype=np.int64) * 1_000_000_000) // fps


def held_index(times_ns: I64, frames_ns: I64) -> I64:
    """For each frame, the index (into ``times_ns``, in its order) of the latest message at or before it, never
    going back (a stamp that goes back holds the newer message); -1 before the first."""
    order = np.argsort(times_ns, kind="stable")
    held = np.searchsorted(times_ns[order], frames_ns, side="right") - 1
    index = np.where(held >= 0, order[np.maximum(held, 0)], -1)
    return np.maximum.accumulate(index) if len(index) else index
