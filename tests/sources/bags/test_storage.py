"""Blocks: messages over one buffer, selected by topic and put in time order (values worked out by hand)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from r2d2_viz.sources.bags.storage import block_of, topic_tuple


def test_block_of_joins_bytes_once_and_sorts_by_time_keeping_file_order_of_ties() -> None:
    topics = topic_tuple(["/b", "/a", "/b"])
    assert topics == ("/a", "/b")
    block = block_of([(30, "/b", b"xyz"), (10, "/a", b"p"), (30, "/a", b"qq"), (20, "/b", b"")], topics)
    assert block.times_ns.tolist() == [10, 20, 30, 30]
    assert [(t, topic, bytes(d)) for t, topic, d in block.messages()] == [
        (10, "/a", b"p"),
        (20, "/b", b""),
        (30, "/b", b"xyz"),
        (30, "/a", b"qq"),
    ]
    assert block.nbytes == 6
    b_rows = block.rows("/b")
    assert b_rows.tolist() == [1, 2]
    only_b = block.take(b_rows)
    assert [bytes(d) for _, d in only_b.pairs()] == [b"", b"xyz"]
    assert len(block.rows("/missing")) == 0
    assert isinstance(block.topic_index, np.ndarray)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_topic_recorded_with_two_types_keeps_its_first_and_says_so_once(tmp_path: Path, storage: str) -> None:
    """Issue 33, finding 7: ``/chatter`` with 5 String then 5 JointState messages (two connections, written by
    rosbags) is read as String — its messages byte for byte as rosbags serialised them — and the 5 others are
    left out with one warning naming the topic, as the ROS 1 reader does (not decoded as JointState, not refused)."""
    from bagmaker import STORAGES, T0, TS, joint_state, string
    from conftest import cli
    from rosbags.rosbag2 import Writer

    from r2d2_viz.sources.bags.bag import open_bag

    bag = tmp_path / "chatter"
    texts = [string(f"hello {k}") for k in range(5)]
    with Writer(bag, version=9, storage_plugin=STORAGES[storage]) as writer:
        said = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=TS)
        other = writer.add_connection("/chatter", "sensor_msgs/msg/JointState", typestore=TS)
        for k in range(5):
            writer.write(said, T0 + k * 100, texts[k])
            writer.write(other, T0 + k * 100 + 50, joint_state(T0, ["swivel"], [float(k)]))
    listed = cli("--bag", str(bag), "--list")
    assert listed.returncode == 0, listed.stderr
    assert [line.split(",")[0] for line in listed.stdout.splitlines()] == [
        "/chatter [std_msgs/msg/String] 5 messages"
    ]  # then rate, bandwidth
    warnings = listed.stderr.splitlines()
    assert len(warnings) == 1 and "/chatter: 5 sensor_msgs/msg/JointState messages left out" in warnings[0]
    notes: list[str] = []
    with open_bag(bag, warn=notes.append) as opened:
        assert [(t, bytes(data)) for t, data in opened.raw("/chatter")] == [(T0 + k * 100, texts[k]) for k in range(5)]
    assert len(notes) == 1
