"""Sampling named values at frame times: golden values by plain Python loops and rosbags' serializer."""

from __future__ import annotations

import numpy as np
import pytest
from bagmaker import TS
from lerobotbags import trajectory, twist

from r2d2_viz.export.lerobot_columns import Series, add_message, frame_times, held_index, ordered
from r2d2_viz.msgs.typestore import MsgError


def test_frame_times_every_1_over_fps_both_ends_included() -> None:
    assert frame_times(1_000, 1_000 + 1_000_000_000, 4).tolist() == [
        1_000, 250_001_000, 500_001_000, 750_001_000, 1_000_001_000,
    ]  # fmt: skip
    assert frame_times(0, 99_999_999, 10).tolist() == [0]
    assert frame_times(5, 4, 30).tolist() == []


def test_held_index_is_the_latest_at_or_before() -> None:
    times = np.array([10, 20, 20, 35], dtype=np.int64)
    frames = np.array([10, 19, 20, 34, 35, 99], dtype=np.int64)
    by_loop = [max(k for k, t in enumerate(times) if t <= f) for f in frames]
    assert held_index(times, frames).tolist() == by_loop == [0, 0, 2, 2, 3, 3]


def test_held_index_never_goes_back_when_stamps_do() -> None:
    times = np.array([10, 30, 20, 40], dtype=np.int64)  # header stamps out of order
    assert held_index(times, np.array([25, 31, 45], dtype=np.int64)).tolist() == [2, 2, 3]


def test_series_holds_each_name_on_its_own() -> None:
    series = Series()
    series.add(10, ["a", "b"], [1.0, 2.0])
    series.add(20, ["b"], [3.0])  # a partial message: a keeps its value
    series.add(30, ["a"], [4.0])
    got = series.at(np.array([10, 25, 30], dtype=np.int64), ["b", "a"])
    assert got.tolist() == [[2.0, 1.0], [3.0, 1.0], [3.0, 4.0]]
    assert series.first_ns() == 10 and series.last_ns() == 20


def test_commands_decode_as_documented() -> None:
    series = Series()
    add_message(series, "trajectory_msgs/msg/JointTrajectory", trajectory(5, [0.25, -0.5]), 7, header=False)
    assert series.names == ["shoulder", "elbow"] and series.values == {"shoulder": [0.25], "elbow": [-0.5]}
    assert series.times["elbow"] == [7]
    add_message(series, "trajectory_msgs/msg/JointTrajectory", trajectory(5, [1.0, 2.0]), 9, header=True)
    assert series.times["elbow"][-1] == 5  # --time header: the message's stamp
    twists = Series()
    add_message(twists, "geometry_msgs/msg/Twist", twist(0.5, -1.25), 3, header=True)  # no header: receive time
    assert twists.names[0] == "linear.x" and twists.values["linear.x"] == [0.5]
    assert twists.values["angular.z"] == [-1.25] and twists.times["angular.z"] == [3]


def test_float64_multi_array_keeps_its_length() -> None:
    array = TS.types["std_msgs/msg/Float64MultiArray"]
    layout = TS.types["std_msgs/msg/MultiArrayLayout"]([], 0)
    series = Series()
    for n in (3, 2):
        data = bytes(TS.serialize_cdr(array(layout, np.arange(n, dtype=np.float64)), "std_msgs/msg/Float64MultiArray"))
        if n == 3:
            add_message(series, "std_msgs/msg/Float64MultiArray", data, 1, header=False)
        else:
            with pytest.raises(MsgError, match="2 values where earlier messages had 3"):
                add_message(series, "std_msgs/msg/Float64MultiArray", data, 2, header=False)
    assert series.names == ["data[0]", "data[1]", "data[2]"]


def test_joint_order_follows_the_robot_then_first_seen() -> None:
    assert ordered(["x", "elbow", "shoulder"], ["shoulder", "elbow"]) == ["shoulder", "elbow", "x"]
