"""A bag's storage files read as one stream in receive-time order (issue 33, finding 1): split bags whose files
overlap in time, a folder of files named out of time order, the latest message taken across files. Bags written
by rosbags (tests/bagmaker.py), the real CLI, the recording read back; expected values worked out by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from bagmaker import T0, BagSpec, joint_state, storage_file, string, write_bag, write_split_bag
from conftest import cli
from rrd import read_recording

from r2d2_viz.robot.model import default_urdf_path
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.bags.merge import merged, overlapping_files
from r2d2_viz.sources.bags.storage import Block

S = 1_000_000_000
JOINTS = ["swivel", "tilt", "periscope"]
URDF = default_urdf_path().read_text()


def _part(times_ns: list[int], description: str | None = None) -> BagSpec:
    """Joint states whose swivel angle is their receive time in seconds after T0 (the golden value is the time)."""
    spec = BagSpec()
    if description is not None:
        spec.add("/robot_description", T0 + times_ns[0], string(description))
    for t in times_ns:
        spec.add("/joint_states", T0 + t, joint_state(T0 + t, JOINTS, [t / S, 0.0, 0.0]))
    return spec


def _swivel(rrd: Path) -> tuple[list[int], list[float]]:
    rows = read_recording(rrd)["/joints/continuous"]
    assert rows.static["SeriesLines:names"][-1] == ["swivel"]
    return rows.times, [v[0] for v in rows.temporal["Scalars:scalars"]]


def _block(times: list[int], topic_index: list[int], topics: tuple[str, ...], payloads: list[bytes]) -> Block:
    lengths = np.array([len(p) for p in payloads], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    return Block(
        np.array(times, dtype=np.int64),
        np.array(topic_index, dtype=np.int32),
        topics,
        memoryview(b"".join(payloads)),
        starts,
        lengths,
    )


def test_files_are_grouped_only_where_their_spans_overlap() -> None:
    # by hand: [0,9] and [5,14] overlap; [14,20] starts where the group ends (no message out of order); None last
    assert overlapping_files([(0, 9), (5, 14), (14, 20), (30, 40), None]) == [[0, 1], [2], [3], [4]]
    assert overlapping_files([(0, 100), (10, 20), (50, 60), (101, 102)]) == [[0, 1, 2], [3]]


def test_the_merge_of_block_streams_is_in_time_order_with_each_message_s_bytes() -> None:
    topics = ("/a", "/b")
    one = iter([_block([0, 10], [0, 0], topics, [b"a0", b"a10"]), _block([20, 30], [0, 1], topics, [b"a20", b"b30"])])
    two = iter([_block([5, 10, 25], [1, 1, 1], topics, [b"b5", b"b10", b"b25"]), _block([40], [1], topics, [b"b40"])])
    out = [m for block in merged([one, two]) for m in block.messages()]
    # by hand: sorted by time; at 10 the first stream's message comes first
    expected = [(0, "/a", b"a0"), (5, "/b", b"b5"), (10, "/a", b"a10"), (10, "/b", b"b10"), (20, "/a", b"a20")]
    expected += [(25, "/b", b"b25"), (30, "/b", b"b30"), (40, "/b", b"b40")]
    assert [(t, topic, bytes(data)) for t, topic, data in out] == expected


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_split_bag_whose_files_overlap_is_replayed_in_receive_time_order(tmp_path: Path, storage: str) -> None:
    first = [k * 100_000_000 for k in range(10)]  # 0.0 … 0.9 s
    second = [550_000_000 + k * 100_000_000 for k in range(10)]  # 0.55 … 1.45 s: overlaps the first file
    bag = write_split_bag(tmp_path / "split", [_part(first, URDF), _part(second)], storage=storage)
    out = tmp_path / "split.rrd"
    result = cli("--bag", str(bag), "--save", str(out))
    assert result.returncode == 0, result.stderr
    assert "went back in time" not in result.stderr and "warning" not in result.stderr
    times, swivel = _swivel(out)
    expected = sorted(first + second)  # by hand: 20 samples, each at its own receive time
    assert times == [T0 + t for t in expected]
    assert swivel == pytest.approx([t / S for t in expected])


def test_a_folder_without_metadata_is_read_in_time_order_whatever_the_names(tmp_path: Path) -> None:
    folder = tmp_path / "day"
    folder.mkdir()
    afternoon_urdf = URDF.replace('link name="box"', 'link name="lunchbox"').replace('link="box"', 'link="lunchbox"')
    assert afternoon_urdf.count("lunchbox") == 2  # the afternoon's robot: its box link renamed
    morning = [k * 100_000_000 for k in range(10)]  # 0.0 … 0.9 s
    afternoon = [10 * S + k * 100_000_000 for k in range(10)]  # 10.0 … 10.9 s
    for name, times, urdf in (("morning", morning, URDF), ("afternoon", afternoon, afternoon_urdf)):
        single = write_bag(tmp_path / name, _part(times, urdf))
        storage_file(single).rename(folder / f"{name}.mcap")  # "afternoon" sorts before "morning"
    with open_bag(folder) as bag:
        assert [f.name for f in bag.files] == ["morning.mcap", "afternoon.mcap"]
        latest = bag.last("/robot_description")
        assert latest is not None and latest[0] == T0 + 10 * S  # the afternoon's, the latest of the folder
        assert bag.last("/joint_states", before_ns=T0 + 5 * S) is not None
        assert bag.last("/joint_states", before_ns=T0 + 5 * S)[0] == T0 + 900_000_000  # type: ignore[index]
    out = tmp_path / "day.rrd"
    result = cli("--bag", str(folder), "--save", str(out))
    assert result.returncode == 0, result.stderr
    times, swivel = _swivel(out)
    assert times == [T0 + t for t in morning + afternoon]
    assert swivel == pytest.approx([t / S for t in morning + afternoon])
    entities = set(read_recording(out))
    assert "/robot/visual/lunchbox/0" in entities and "/robot/visual/box/0" not in entities  # the latest model


def test_a_topic_of_another_type_in_a_later_file_is_left_out_there_and_said_once(tmp_path: Path) -> None:
    """Finding 7 across files: a folder whose first file has /chatter as String, the second as JointState."""
    folder = tmp_path / "chatter"
    folder.mkdir()
    first = BagSpec(types={"/chatter": "std_msgs/msg/String"})
    second = BagSpec(types={"/chatter": "sensor_msgs/msg/JointState"})
    for k in range(3):
        first.add("/chatter", T0 + k, string(f"hello {k}"))
        second.add("/chatter", T0 + S + k, joint_state(T0, ["swivel"], [float(k)]))
    for name, spec in (("a", first), ("b", second)):
        storage_file(write_bag(tmp_path / name, spec)).rename(folder / f"{name}.mcap")
    listed = cli("--bag", str(folder), "--list")
    assert listed.returncode == 0, listed.stderr
    assert [line.split(",")[0] for line in listed.stdout.splitlines()] == [
        "/chatter [std_msgs/msg/String] 3 messages"
    ]  # then rate, bandwidth
    assert len(listed.stderr.splitlines()) == 1
    assert "/chatter (sensor_msgs/msg/JointState in b.mcap, left out)" in listed.stderr
    with open_bag(folder, warn=lambda _: None) as bag:
        assert [bytes(d) for _, d in bag.raw("/chatter")] == [string(f"hello {k}") for k in range(3)]
