"""MCAP records, on bytes laid out by hand from the spec (https://mcap.dev/spec): a record is an opcode, a u64
length and its body; a Message record's body is channel id u16, sequence u32, log time u64, publish time u64, data;
a Chunk Index record's is start, end, chunk offset, chunk length (u64 each), then a u32-sized map of channel id u16 →
message index offset u64."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from r2d2_viz.sources.bags.mcap_records import (
    BrokenError,
    ChunkIndex,
    chunk_index,
    holds,
    merge_blocks,
    merged_chunks,
    message_times,
    overlapping,
    string_at,
    walk_messages,
    walk_records,
)
from r2d2_viz.sources.bags.storage import Block


def _record(op: int, body: bytes) -> bytes:
    return bytes([op]) + struct.pack("<Q", len(body)) + body


def _message(channel: int, log_time: int, data: bytes) -> bytes:
    return _record(0x05, struct.pack("<HIQQ", channel, 7, log_time, log_time + 1) + data)


def test_records_and_strings() -> None:
    buf = memoryview(_record(0x03, b"abc") + _record(0x04, b"") + _record(0x05, b"x" * 10)[:-1])
    walked = walk_records(buf, 0, len(buf))
    assert next(walked) == (0x03, 9, 12) and next(walked) == (0x04, 21, 21)
    with pytest.raises(BrokenError, match="runs past the end"):
        next(walked)  # the third claims 10 bytes, 9 are there
    text = struct.pack("<I", 5) + b"/odom" + struct.pack("<I", 9) + b"short"
    assert string_at(text, 0) == ("/odom", 9)
    with pytest.raises(BrokenError, match="string runs past"):
        string_at(text, 9)


def test_a_chunks_messages_walked_record_by_record() -> None:
    chunk = (
        _message(1, 30, b"one")
        + _record(0x03, b"a schema between them")
        + _message(2, 10, b"two!")
        + _message(3, 20, b"three")
        + _message(1, 5, b"")
    )
    block = walk_messages(memoryview(chunk), ("/a", "/c"), {1: 0, 3: 1})  # channel 2 is not wanted
    assert block.times_ns.tolist() == [30, 20, 5]  # file order (the scan puts them in time order)
    assert [block.topics[i] for i in block.topic_index] == ["/a", "/c", "/a"]
    assert [bytes(block.data(i)) for i in range(3)] == [b"one", b"three", b""]
    assert list(message_times(memoryview(chunk), 0, len(chunk))) == [(1, 30), (2, 10), (3, 20), (1, 5)]
    with pytest.raises(BrokenError, match="past its chunk"):
        walk_messages(memoryview(chunk[:-1]), ("/a",), {1: 0})


def test_a_chunk_index() -> None:
    pairs = struct.pack("<HQ", 1, 5000) + struct.pack("<HQ", 4, 6000)
    body = struct.pack("<QQQQ", 10, 20, 100, 900) + struct.pack("<I", len(pairs)) + pairs
    index = chunk_index(body, 0, len(body), 1000)  # type: ignore[arg-type]
    assert index == ChunkIndex(10, 20, 100, 900, {1: 5000, 4: 6000})
    assert holds(index, {4: 0}) and not holds(index, {2: 0, 3: 1})
    assert holds(ChunkIndex(10, 20, 100, 900, {}), {2: 0})  # no message index offsets: it may hold them
    with pytest.raises(BrokenError, match="points past the end"):
        chunk_index(body, 0, len(body), 999)  # type: ignore[arg-type]
    with pytest.raises(BrokenError, match="runs past its record"):
        chunk_index(body, 0, len(body) - 1, 1000)  # type: ignore[arg-type]


def test_chunks_that_overlap_in_time_are_grouped_and_merged_in_time_order() -> None:
    a, b, c, d = (ChunkIndex(s, e, k, 1, {}) for k, (s, e) in enumerate([(0, 10), (5, 20), (21, 30), (30, 40)]))
    assert list(overlapping([a, b, c, d])) == [[a, b], [c, d]]  # c starts after b ends; d where c ends
    assert list(overlapping([])) == []

    def block(times: list[int], data: list[bytes]) -> Block:
        starts = np.cumsum([0] + [len(x) for x in data[:-1]]).astype(np.int64)
        lengths = np.array([len(x) for x in data], dtype=np.int64)
        index = np.zeros(len(times), dtype=np.int32)
        return Block(np.array(times, dtype=np.int64), index, ("/t",), memoryview(b"".join(data)), starts, lengths)

    merged = merge_blocks([block([0, 6, 9], [b"a0", b"a6", b"a9"]), block([5, 7, 20], [b"b5", b"b7", b"b20"])])
    assert merged.times_ns.tolist() == [0, 5, 6, 7, 9, 20]
    assert [bytes(merged.data(i)) for i in range(len(merged))] == [b"a0", b"b5", b"a6", b"b7", b"a9", b"b20"]


def test_overlapping_chunks_are_read_as_the_merge_reaches_them() -> None:
    """Chunks by hand: ``long`` spans 0..90 (written last: file offset 300), ``a`` 0..20, ``b`` 30..50, ``c`` 60..90.
    Each is read only once the merge has given everything before its start (``b`` after 20, not at the start);
    messages received at one time come in the file's order (``a``'s 20 before ``long``'s 20; at 90, ``c`` first);
    the blocks together are every message in time order."""

    def block(times: list[int], name: str) -> Block:
        data = [f"{name}{t}".encode() for t in times]
        starts = np.cumsum([0] + [len(x) for x in data[:-1]]).astype(np.int64)
        lengths = np.array([len(x) for x in data], dtype=np.int64)
        index = np.zeros(len(times), dtype=np.int32)
        return Block(np.array(times, dtype=np.int64), index, ("/t",), memoryview(b"".join(data)), starts, lengths)

    spans = {"a": (0, 20, 0), "b": (30, 50, 100), "c": (60, 90, 200), "long": (0, 90, 300)}
    contents = {"a": [0, 10, 20], "b": [30, 40, 50], "c": [60, 90], "long": [5, 20, 45, 90]}
    chunks = {name: ChunkIndex(s, e, off, 1, {}) for name, (s, e, off) in spans.items()}
    read: list[str] = []
    given: list[bytes] = []

    def reader(c: ChunkIndex) -> Block:
        name = next(n for n, x in chunks.items() if x is c)
        read.append(f"{name} after {len(given)}")
        return block(contents[name], name)

    for out in merged_chunks(list(chunks.values()), reader, lambda c: (c.start_ns, c.offset)):
        given += [bytes(out.data(i)) for i in range(len(out))]
    assert given == [
        b"a0",
        b"long5",
        b"a10",
        b"a20",
        b"long20",
        b"b30",
        b"b40",
        b"long45",
        b"b50",
        b"c60",
        b"c90",
        b"long90",
    ]
    assert read == ["a after 0", "long after 0", "b after 5", "c after 9"]


def test_big_interleaved_messages_are_given_run_by_run_without_a_copy() -> None:
    """Two chunks by hand whose messages interleave: 300 kB frames at 0, 20, 40 and 4-byte samples at 10, 30. Each
    run (one message here) comes as a view of its own chunk's buffer, in time order; tiny messages that interleave
    are merged into one block instead (the test above)."""
    frames = [bytes([k]) * 300_000 for k in range(3)]
    big = Block(
        np.array([0, 20, 40], dtype=np.int64), np.zeros(3, dtype=np.int32), ("/t",), memoryview(b"".join(frames)),
        np.array([0, 300_000, 600_000], dtype=np.int64), np.full(3, 300_000, dtype=np.int64),
    )  # fmt: skip
    small = Block(
        np.array([10, 30], dtype=np.int64), np.zeros(2, dtype=np.int32), ("/t",), memoryview(b"s010s030"),
        np.array([0, 4], dtype=np.int64), np.full(2, 4, dtype=np.int64),
    )  # fmt: skip
    chunks = [ChunkIndex(0, 40, 0, 1, {}), ChunkIndex(10, 30, 100, 1, {})]
    out = list(merged_chunks(chunks, lambda c: big if c.offset == 0 else small, lambda c: (c.start_ns, c.offset)))
    assert [bytes(b.data(i)) for b in out for i in range(len(b))] == [frames[0], b"s010", frames[1], b"s030", frames[2]]
    assert [b.buffer.obj for b in out] == [big.buffer.obj, small.buffer.obj] * 2 + [big.buffer.obj]
