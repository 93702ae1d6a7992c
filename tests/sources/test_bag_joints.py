"""A bag's /joint_states through its one pass (sources/playback.BagPass, decoded by bag_joints) and the
/robot_description reader, on bags written by rosbags: values must equal what rosbags' own deserializer reads from
the same bytes (bit for bit), times the bag's receive times or stamps."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from bagmaker import T0, TS, BagSpec, joint_state, storage_file, string, write_bag
from conftest import REPO
from rosbags.rosbag2 import Reader

from r2d2_viz.errors import BagError
from r2d2_viz.sources.bag_joints import TimeSource, read_robot_description
from r2d2_viz.sources.bags.bag import Bag, open_bag
from r2d2_viz.sources.playback import BagPass, Segment, bag_topics_read

ARM = ["shoulder", "elbow", "wrist", "gripper"]


def _arm_bag(tmp_path: Path, storage: str = "mcap", version: int = 9, n: int = 300) -> Path:
    """An arm publisher (3 joints, 100 Hz) and a gripper publisher (1 joint, every 3rd), header stamps 1 ms
    before receipt, like two real publishers."""
    rng = np.random.default_rng(7)
    spec = BagSpec()
    for k in range(n):
        t = T0 + k * 10**7
        spec.add("/joint_states", t, joint_state(t - 10**6, ARM[:3], rng.normal(size=3), frame_id="base"))
        if k % 3 == 0:
            spec.add("/joint_states", t + 5 * 10**6, joint_state(t + 4 * 10**6, ["gripper"], [k / n]))
    return write_bag(tmp_path / "arm", spec, storage=storage, version=version)


def _rosbags_reference(path: Path) -> tuple[list[int], list[int], list[dict[str, float]]]:
    """Receive times, header stamps and {name: position} of every message, by rosbags alone."""
    receive, header, values = [], [], []
    with Reader(path) as reader:
        for _, t, data in reader.messages():
            msg = TS.deserialize_cdr(data, "sensor_msgs/msg/JointState")
            receive.append(t)
            header.append(msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec)
            values.append(dict(zip(msg.name, msg.position.tolist(), strict=True)))
    return receive, header, values


def _pass(bag: Bag, actuated: list[str], time: TimeSource = "receive") -> BagPass:
    """The bag's joint states alone, read once (what a replay's pass does beside /tf and the displays)."""
    return BagPass(bag, [Segment(bag_topics_read(bag, actuated, {}))], actuated=actuated, displays={}, time=time)


def _all(source: BagPass, max_samples: int = 64):
    chunks = [w.joints for w in source.windows(max_samples) if w.joints is not None]
    assert all(0 < len(c) <= max_samples for c in chunks)
    times = np.concatenate([c.times_ns for c in chunks])
    rows = []
    for c in chunks:
        for row in c.positions:
            rows.append({j: v for j, v in zip(c.joints, row.tolist(), strict=True) if not np.isnan(v)})
    return times, rows


@pytest.mark.parametrize(("storage", "version"), [("mcap", 9), ("sqlite3", 8), ("sqlite3", 5), ("mcap", 4)])
def test_reads_exactly_what_rosbags_reads(tmp_path: Path, storage: str, version: int) -> None:
    path = _arm_bag(tmp_path, storage, version)
    receive, header, values = _rosbags_reference(storage_file(path))
    with open_bag(path) as bag:
        times, rows = _all(_pass(bag, ARM))
        assert times.tolist() == receive
        assert rows == values  # a message's joints only: the others are NaN (keep their last value)
        header_times, _ = _all(_pass(bag, ARM, time="header"))
        assert header_times.tolist() == header


def test_chunk_columns_are_robot_joints_in_robot_order(tmp_path: Path) -> None:
    with open_bag(_arm_bag(tmp_path, n=10)) as bag:
        source = _pass(bag, ["gripper", "wrist", "elbow", "shoulder", "unused"])
        assert source.joints is not None
        assert source.joints.joints == ("gripper", "wrist", "elbow", "shoulder", "unused")
        chunk = next(w.joints for w in source.windows(100) if w.joints is not None)
    assert chunk.joints == ("gripper", "wrist", "elbow", "shoulder")
    assert chunk.positions.shape == (len(chunk.times_ns), 4) and chunk.positions.dtype == np.float64
    assert np.all(np.diff(chunk.times_ns) >= 0)


def test_unknown_names_ignored_with_one_warning(tmp_path: Path) -> None:
    spec = BagSpec()
    for k in range(50):
        spec.add("/joint_states", T0 + k, joint_state(T0 + k, ["elbow", "caster_wheel"], [k, 2 * k]))
    warnings: list[str] = []
    with open_bag(write_bag(tmp_path / "b", spec), warn=warnings.append) as bag:
        _times, rows = _all(_pass(bag, ARM), 7)
    assert rows == [{"elbow": float(k)} for k in range(50)]
    assert len(warnings) == 1 and "caster_wheel" in warnings[0] and "not actuated joints" in warnings[0]


def test_mismatched_lengths_skipped_and_counted_once(tmp_path: Path) -> None:
    spec = BagSpec()
    for k in range(30):
        names, pos = (["elbow", "wrist"], [k]) if k % 10 == 0 else (["elbow"], [k])  # 3 bad messages
        spec.add("/joint_states", T0 + k, joint_state(T0 + k, names, pos))
    warnings: list[str] = []
    with open_bag(write_bag(tmp_path / "b", spec), warn=warnings.append) as bag:
        times, _rows = _all(_pass(bag, ARM), 8)
    assert times.tolist() == [T0 + k for k in range(30) if k % 10]
    assert warnings == [f"{tmp_path / 'b'}: /joint_states: skipped 3 messages whose name and position lengths differ"]


def test_big_endian_messages_decoded_by_rosbags(tmp_path: Path) -> None:
    msg = TS.deserialize_cdr(joint_state(T0, ["elbow", "wrist"], [0.25, -1.5]), "sensor_msgs/msg/JointState")
    big = bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/JointState", little_endian=False))
    spec = BagSpec().add("/joint_states", T0 + 5, big).add("/joint_states", T0 + 6, joint_state(T0, ["elbow"], [1]))
    with open_bag(write_bag(tmp_path / "b", spec)) as bag:
        times, rows = _all(_pass(bag, ARM))
        header, header_rows = _all(_pass(bag, ARM, time="header"))
    assert rows == [{"elbow": 0.25, "wrist": -1.5}, {"elbow": 1.0}]
    assert times.tolist() == [T0 + 5, T0 + 6]
    # by their stamps both are at T0: one sample, the second applied after the first (issue 29)
    assert header.tolist() == [T0] and header_rows == [{"elbow": 1.0, "wrist": -1.5}]


def test_header_stamps_that_go_back_are_held_with_one_warning(tmp_path: Path) -> None:
    stamps = [5, 6, 3, 7, 1, 8]
    spec = BagSpec()
    for k, s in enumerate(stamps):
        spec.add("/joint_states", T0 + k, joint_state(T0 + s, ["elbow"], [k]))
    warnings: list[str] = []
    with open_bag(write_bag(tmp_path / "b", spec), warn=warnings.append) as bag:
        times, _ = _all(_pass(bag, ARM, time="header"), 2)
    assert (times - T0).tolist() == [5, 6, 6, 7, 7, 8]
    assert len(warnings) == 1 and "2 header stamps went back" in warnings[0]


def test_wrong_type_on_joint_states_is_one_line(tmp_path: Path) -> None:
    spec = BagSpec(types={"/joint_states": "std_msgs/msg/String"}).add("/joint_states", T0, string("x"))
    with open_bag(write_bag(tmp_path / "b", spec)) as bag, pytest.raises(BagError) as info:
        bag_topics_read(bag, ARM, {})
    assert (
        str(info.value)
        == f"{tmp_path / 'b'}: /joint_states is std_msgs/msg/String, expected sensor_msgs/msg/JointState"
    )


def test_no_joint_states_no_chunks(tmp_path: Path) -> None:
    spec = BagSpec().add("/robot_description", T0, string("<robot/>"))
    with open_bag(write_bag(tmp_path / "b", spec)) as bag:
        assert bag_topics_read(bag, ARM, {}) == ()  # the pass does not read it
        windows = list(BagPass(bag, [Segment(("/joint_states",))], actuated=ARM, displays={}).windows(10))
        assert windows == []


def test_robot_description_is_the_latest(tmp_path: Path) -> None:
    spec = BagSpec().add("/robot_description", T0, string("<robot name='old'/>"))
    spec.add("/robot_description", T0 + 9, string("<robot name='new'/>"))
    with open_bag(write_bag(tmp_path / "b", spec)) as bag:
        assert read_robot_description(bag) == "<robot name='new'/>"
    with open_bag(REPO / "tests/data/bags/talker_db3/talker.db3") as bag:  # a String recorded by ROS 2
        assert read_robot_description(bag) is None
        assert read_robot_description(bag, "/topic") == "Hello, world! 9"


@pytest.mark.parametrize("publishers", ["one, every joint in order", "two of one length, names swapped"])
def test_one_layout_for_all_and_layouts_of_one_length_read_as_rosbags_reads(tmp_path: Path, publishers: str) -> None:
    """Issue 38: a block whose messages all share one layout with every joint in the robot's order (the 1 h
    JointState bag's) is read without gathers; layouts of one byte length (names swapped) still apart. Values bit
    for bit as rosbags deserialises them."""
    rng = np.random.default_rng(3)
    spec = BagSpec()
    for k in range(200):
        t = T0 + k * 10**7
        names = ARM if publishers.startswith("one") or k % 2 else ["elbow", "shoulder", "gripper", "wrist"]
        spec.add("/joint_states", t, joint_state(t - 10**6, names, rng.normal(size=4)))
    path = write_bag(tmp_path / "b", spec)
    receive, header, values = _rosbags_reference(storage_file(path))
    with open_bag(path) as bag:
        for max_samples in (64, 1000):
            times, rows = _all(_pass(bag, ARM), max_samples)
            assert times.tolist() == receive
            assert rows == values
            assert _all(_pass(bag, ARM, time="header"), max_samples)[0].tolist() == header
