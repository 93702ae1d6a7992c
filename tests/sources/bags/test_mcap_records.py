"""MCAP records read against the spec (https://mcap.dev/spec) on files rosbags' writer made: the summary's chunk
index covers every message rosbags reads back, and a chunk's message indexes find exactly those messages."""

from __future__ import annotations

import mmap
from pathlib import Path

from bagmaker import T0, BagSpec, joint_state, storage_file, string, write_bag
from rosbags.rosbag2 import Reader

from r2d2_viz.sources.bags.mcap_records import Summary, chunk_data, indexed, read_summary, walk


def _file(tmp_path: Path) -> Path:
    spec = BagSpec().add("/robot_description", T0, string("<robot/>"))
    for k in range(12000):  # rosbags writes chunks of about 1 MB: several chunks
        spec.add("/joint_states", T0 + 1000 * k, joint_state(T0 + 1000 * k, ["a", "b"], [k, -k]))
    return storage_file(write_bag(tmp_path / "b", spec))


def test_the_summary_and_message_indexes_find_what_rosbags_reads(tmp_path: Path) -> None:
    file = _file(tmp_path)
    with Reader(file) as reader:
        expected = [(t, bytes(d)) for c, t, d in reader.messages() if c.topic == "/joint_states"]
    with file.open("rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as buf:
        summary = read_summary(buf)
        assert isinstance(summary, Summary)
        topics = {c.topic: c.id for c in summary.channels.values()}
        assert summary.counts[topics["/joint_states"]] == 12000
        assert summary.span == (T0, T0 + 1000 * 11999)
        assert len(summary.chunks) > 1
        wanted = {topics["/joint_states"]: 0}
        got_indexed, got_walked = [], []
        for c in summary.chunks:
            data = chunk_data(buf, c.offset, c.offset + c.length)
            for blocks, found in (
                (got_indexed, indexed(buf, c, ("/joint_states",), wanted, data)),
                (got_walked, walk(data, ("/joint_states",), wanted)),
            ):
                if found is not None:
                    blocks += [(t, bytes(d)) for t, d in found.pairs()]
        del data, found  # views of the map
    assert got_indexed == expected
    assert got_walked == expected


def test_a_file_without_footer_has_no_summary_and_says_so(tmp_path: Path) -> None:
    file = _file(tmp_path)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(file.read_bytes()[:-100])
    with cut.open("rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as buf:
        assert read_summary(buf) == "the file breaks off (no footer, no index)"
