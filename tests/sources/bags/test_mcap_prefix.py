"""Compressed MCAP chunks read only up to their last wanted message (sources/bags/mcap_prefix.py): the messages are
those rosbags' own reader gives, each chunk decompressed up to the end of the last one wanted (its size worked out
by hand from what was written); a stretch asked for gives its messages."""

from __future__ import annotations

from pathlib import Path

import pytest
from bagmaker import T0, TS, string
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode

from r2d2_viz.sources.bags.mcap_scan import McapScan

MS = 1_000_000
BIG = 200_000


def _bag(tmp_path: Path, fmt: CompressionFormat) -> Path:
    """Each 10 ms: a small /a, then a ~200 kB /big (rosbags closes a chunk past 1 MiB: six of each a chunk)."""
    path = tmp_path / fmt.name
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.set_compression(CompressionMode.STORAGE, fmt)
    with writer:
        small = writer.add_connection("/a", "std_msgs/msg/String", typestore=TS)
        big = writer.add_connection("/big", "std_msgs/msg/String", typestore=TS)
        for k in range(30):
            writer.write(small, T0 + k * 10 * MS, string(f"a{k}"))
            writer.write(big, T0 + k * 10 * MS + 1, string(chr(65 + k % 26) * BIG))
    return next(path.glob("*.mcap"))


def _reference(path: Path, topic: str) -> list[tuple[int, bytes]]:
    with Reader(path.parent) as reader:
        return [(t, bytes(d)) for c, t, d in reader.messages() if c.topic == topic]


@pytest.mark.parametrize("fmt", [CompressionFormat.ZSTD])
def test_a_small_topic_decompresses_each_chunk_up_to_its_last_message(tmp_path: Path, fmt: CompressionFormat) -> None:
    path = _bag(tmp_path, fmt)
    scan = McapScan(path)
    try:
        blocks = list(scan.blocks(["/a"]))
        got = [(int(b.times_ns[i]), bytes(b.data(i))) for b in blocks for i in range(len(b))]
        assert got == _reference(path, "/a")
        # by hand: a chunk holds six pairs; its last /a comes before its last /big, which is not decompressed
        record = 9 + 2 + 8 + 8 + 4  # an MCAP message record's head: opcode, length, channel, sequence, two times
        big_record = record + 4 + 4 + BIG + 1 + 3  # CDR header, string length, the text and its NUL, padding
        for b in blocks[:-1]:
            assert len(b) == 6 and b.read_nbytes < 6 * big_record
            assert b.read_nbytes >= 5 * big_record
        # a stretch ending inside a chunk: the same messages (that chunk read whole: its index reaches past the part)
        stretch = list(scan.blocks(["/a"], start_ns=T0, stop_ns=T0 + 25 * MS))
        assert [int(t) for b in stretch for t in b.times_ns] == [T0, T0 + 10 * MS, T0 + 20 * MS]
        # the big topic itself: every chunk whole, every message as rosbags reads it
        bigs = list(scan.blocks(["/big"]))
        assert [bytes(b.data(i)) for b in bigs for i in range(len(b))] == [d for _, d in _reference(path, "/big")]
    finally:
        scan.close()
