"""Reading an MCAP file: what it finds must be what rosbags reads from it — through the file's own index (summary,
chunk indexes, message indexes) several topics at once, chunks that hold none of them never read; without a usable
summary by a scan from the start; from a damaged one what can be read. Damage is made by editing bytes at offsets
worked out from the MCAP spec (https://mcap.dev/spec) and from rosbags' own reading of the file's chunk index."""

from __future__ import annotations

import os
import struct
import tracemalloc
import zlib
from collections.abc import Callable
from pathlib import Path

import pytest
from bagmaker import T0, TS, TYPES, BagSpec, joint_state, storage_file, string, tf_message, write_bag
from rosbags.rosbag2 import CompressionFormat, CompressionMode, Reader, StoragePlugin, Writer
from rosbags.rosbag2.storage_mcap import ChunkInfo, McapReader

import r2d2_viz.sources.bags.mcap_scan as mcap_scan
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.bags.mcap_scan import McapScan

MS = 1_000_000
Message = tuple[int, str, bytes]


def _intact(tmp_path: Path, n: int = 5000) -> Path:
    """rosbags' writer closes a chunk past 1 MiB: 20,000 of these messages fill two."""
    spec = BagSpec().add("/robot_description", T0, string("<robot/>"))
    for k in range(n):
        spec.add("/joint_states", T0 + k, joint_state(T0 + k, ["a", "b"], [k, -k]))
    return storage_file(write_bag(tmp_path / "b", spec))


def _mixed(tmp_path: Path, name: str = "mixed") -> Path:
    """Three topics interleaved over several chunks: joint states every ms, /tf every 2nd, a 20 kB string every
    10th."""
    spec = BagSpec()
    for k in range(1500):
        t = T0 + k * MS
        spec.add("/joint_states", t, joint_state(t, ["a"], [k]))
        if k % 2 == 0:
            spec.add("/tf", t + 1, tf_message([(t, "odom", "base", (k, 0, 0), (0, 0, 0, 1))]))
        if k % 10 == 0:
            spec.add("/robot_description", t + 2, string(f"{k}" * 10_000))
    return storage_file(write_bag(tmp_path / name, spec))


def _apart(tmp_path: Path, **kw: object) -> Path:
    """Two topics in chunks of their own: big strings for 400 ms (two chunks and part of a third), then joint
    states."""
    spec = BagSpec()
    for k in range(400):
        spec.add("/robot_description", T0 + k * MS, string("x" * 5000))
    for k in range(400, 3000):
        spec.add("/joint_states", T0 + k * MS, joint_state(T0 + k, ["a", "b"], [k, -k]))
    if not kw:
        return storage_file(write_bag(tmp_path / "apart", spec))
    path = tmp_path / "apart"
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)  # chunks compressed with zstd
    writer.open()
    connections = {}
    for topic, t, data in spec.messages:
        if topic not in connections:
            connections[topic] = writer.add_connection(topic, spec.types[topic], typestore=TS)
        writer.write(connections[topic], t, data)
    writer.close()
    return storage_file(path)


def _rosbags(file: Path, topics: set[str]) -> list[Message]:
    """rosbags' own reader: the messages on ``topics``, in time order."""
    with Reader(file) as reader:
        wanted = [c for c in reader.connections if c.topic in topics]
        return sorted(((t, c.topic, bytes(d)) for c, t, d in reader.messages(connections=wanted)), key=lambda m: m[0])


def _read(scan: McapScan, topics: list[str], **kw: int | None) -> list[Message]:
    return [(t, topic, bytes(d)) for block in scan.blocks(topics, **kw) for t, topic, d in block.messages()]


def _chunks(file: Path) -> tuple[list[ChunkInfo], dict[int, str]]:
    """The chunk index and channels as rosbags reads them."""
    reader = McapReader(file)
    reader.open()
    try:
        return list(reader.chunks), {c.id: c.topic for c in reader.channels.values()}
    finally:
        reader.close()


def _footer(data: bytes | bytearray) -> tuple[int, int, int]:
    """(footer record offset, summary start, summary offset start): the footer is the 29-byte record before the
    closing magic (spec: Footer)."""
    at = len(data) - 8 - 29
    assert data[at] == 0x02
    start, offsets = struct.unpack_from("<QQ", data, at + 9)
    return at, start, offsets


def _summary_records(data: bytes | bytearray) -> list[tuple[int, int]]:
    """(op, record offset) of each record of the summary section."""
    at_footer, at, offsets = _footer(data)
    end = offsets or at_footer
    out = []
    while at < end:
        (size,) = struct.unpack_from("<Q", data, at + 1)
        out.append((data[at], at))
        at += 9 + size
    return out


def test_an_intact_file_scans_like_rosbags_reads_it(tmp_path: Path) -> None:
    file = _intact(tmp_path)
    scan = McapScan(file)
    assert {t: (i.msgtype, i.count) for t, i in scan.topics.items()} == {
        "/robot_description": ("std_msgs/msg/String", 1),
        "/joint_states": ("sensor_msgs/msg/JointState", 5000),
    }
    assert "string data" in scan.topics["/robot_description"].definition  # the schema rosbags wrote
    assert scan.note == "" and scan.chunks is not None and scan.span == (T0, T0 + 4999)
    assert _read(scan, ["/joint_states"]) == _rosbags(file, {"/joint_states"})


def test_several_topics_at_once_through_the_index_like_rosbags(tmp_path: Path) -> None:
    file = _mixed(tmp_path)
    chunks, _ = _chunks(file)
    assert len(chunks) > 3 and all(len(c.message_index_offsets) == 3 for c in chunks)  # every chunk mixes them
    scan = McapScan(file)
    for topics in (["/joint_states", "/tf"], ["/tf", "/robot_description", "/joint_states"], ["/tf"]):
        got = _read(scan, topics)
        assert got == _rosbags(file, set(topics)) and len(got) > 700
        assert len(list(scan.blocks(topics))) > 1
    assert scan.problems == {}


def test_chunks_without_a_wanted_topic_are_never_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    file = _apart(tmp_path)
    expected = _rosbags(file, {"/joint_states"})
    chunks, channels = _chunks(file)
    holds = [{channels[c] for c in info.message_index_offsets} for info in chunks]
    assert holds[0] == {"/robot_description"} and {"/joint_states"} in holds
    # the first chunk's records overwritten (spec: Chunk = op, length, start, end, size, crc, compression, records)
    data = bytearray(file.read_bytes())
    first = chunks[0]
    (name,) = struct.unpack_from("<I", data, first.chunk_start_offset + 9 + 28)
    records = first.chunk_start_offset + 9 + 32 + name + 8
    data[records : records + 4096] = b"\xff" * 4096
    file.write_bytes(bytes(data))

    scan = McapScan(file)
    reads: list[int] = []
    chunk_data = mcap_scan.chunk_data  # decompresses and checks one chunk
    monkeypatch.setattr(mcap_scan, "chunk_data", lambda buf, a, b, **kw: reads.append(a) or chunk_data(buf, a, b, **kw))
    assert _read(scan, ["/joint_states"]) == expected and scan.problems == {}
    assert sorted(reads) == [c.chunk_start_offset for c, h in zip(chunks, holds, strict=True) if "/joint_states" in h]
    # a stretch within one chunk reads that chunk alone
    reads.clear()
    assert _read(scan, ["/joint_states"], start_ns=T0 + 2999 * MS) == expected[-1:]
    assert reads == [chunks[-1].chunk_start_offset]


def test_start_and_stop_and_the_last_before(tmp_path: Path) -> None:
    file = _mixed(tmp_path)
    everything = _rosbags(file, {"/joint_states", "/tf", "/robot_description"})
    chunks, _ = _chunks(file)
    edge = chunks[1].message_start_time  # a stretch that starts on a chunk's first message
    scan = McapScan(file)
    for start, stop in [(T0 + 100 * MS, T0 + 900 * MS), (edge, edge + 1), (edge, None), (None, T0 + 3), (T0, T0)]:
        got = _read(scan, ["/joint_states", "/tf", "/robot_description"], start_ns=start, stop_ns=stop)
        lo, hi = start if start is not None else 0, stop if stop is not None else 2**64
        assert got == [m for m in everything if lo <= m[0] < hi], (start, stop)
    for topic in ("/tf", "/robot_description"):
        mine = [m for m in everything if m[1] == topic]
        assert scan.last(topic) == (mine[-1][0], mine[-1][2])
        before = T0 + 777 * MS
        last = [m for m in mine if m[0] < before][-1]
        assert scan.last(topic, before_ns=before) == (last[0], last[2])
    assert scan.last("/tf", before_ns=T0) is None and scan.last("/nothing") is None


def test_chunks_that_overlap_in_time(tmp_path: Path) -> None:
    """Messages written out of time order (rosbags' writer keeps them as given): the first chunk spans 10..100 ns
    but holds the description only at 10; the second, 50..90, holds it at 80. The last description is the one at 80,
    and a pass gives every message in time order."""
    spec = BagSpec(types={**TYPES, "/pad": "std_msgs/msg/String"})
    pad = string("p" * 600_000)  # two of these fill a chunk
    spec.add("/robot_description", T0 + 10, string("first")).add("/pad", T0 + 100, pad).add("/pad", T0 + 100, pad)
    spec.add("/pad", T0 + 50, pad).add("/robot_description", T0 + 80, string("later")).add("/pad", T0 + 90, pad)
    file = storage_file(write_bag(tmp_path / "overlap", spec))
    chunks, _ = _chunks(file)
    assert [(c.message_start_time - T0, c.message_end_time - T0) for c in chunks[:2]] == [(10, 100), (50, 90)]
    scan = McapScan(file)
    assert scan.last("/robot_description") == (T0 + 80, string("later"))
    assert scan.last("/robot_description", before_ns=T0 + 80) == (T0 + 10, string("first"))
    expected = _rosbags(file, {"/robot_description", "/pad"})
    assert _read(scan, ["/robot_description", "/pad"]) == expected
    assert [t - T0 for t, _, _ in expected] == [10, 50, 80, 90, 100, 100]


def _edit_summary(data: bytearray, how: str) -> None:
    at_footer, start, _ = _footer(data)
    if how == "outside":  # the footer's summary start past the end of the file
        struct.pack_into("<Q", data, at_footer + 9, len(data) + 100)
    elif how == "absent":  # a valid file without a summary (spec: summary start 0)
        struct.pack_into("<QQI", data, at_footer + 9, 0, 0, 0)
    elif how == "record":  # the first summary record says it runs past the end
        struct.pack_into("<Q", data, start + 1, 2**40)
    elif how == "chunk index":  # a chunk index pointing past the end of the file
        at = next(at for op, at in _summary_records(data) if op == 0x08)
        struct.pack_into("<Q", data, at + 9 + 16, len(data) + 10)


@pytest.mark.parametrize("how", ["outside", "absent", "record", "chunk index"])
def test_a_damaged_or_absent_summary_falls_back_to_the_scan(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, how: str
) -> None:
    file = _mixed(tmp_path)
    everything = _rosbags(file, {"/joint_states", "/tf", "/robot_description"})
    chunks, _ = _chunks(file)
    data = bytearray(file.read_bytes())
    _edit_summary(data, how)
    file.write_bytes(bytes(data))
    scan = McapScan(file)
    assert bool(scan.note) == (how != "absent")
    assert scan.topics["/joint_states"].count == 1500 and scan.span == (everything[0][0], everything[-1][0])
    assert _read(scan, ["/joint_states", "/tf", "/robot_description"]) == everything
    reads: list[int] = []
    chunk_data = mcap_scan.chunk_data  # decompresses and checks one chunk
    monkeypatch.setattr(mcap_scan, "chunk_data", lambda buf, a, b, **kw: reads.append(a) or chunk_data(buf, a, b, **kw))
    assert _read(scan, ["/tf"], start_ns=T0 + 10 * MS, stop_ns=T0 + 20 * MS) == [
        m for m in everything if m[1] == "/tf" and T0 + 10 * MS <= m[0] < T0 + 20 * MS
    ]
    # a stretch reads its chunk alone: the walk that opened the file noted where each chunk is, and when
    assert len(chunks) > 3 and reads == [c.chunk_start_offset for c in chunks if c.message_start_time <= T0 + 20 * MS]
    warnings: list[str] = []
    with open_bag(file, warn=warnings.append) as bag:
        got = [(t, bytes(d)) for t, d in bag.raw("/joint_states")]
        last_tf = [m for m in everything if m[1] == "/tf"][-1]
        assert bag.last("/tf") == (last_tf[0], last_tf[2])
    assert got == [(t, d) for t, topic, d in everything if topic == "/joint_states"]
    assert len(warnings) == (how != "absent") and all(str(file) in w for w in warnings), warnings


def _damage_chunk(file: Path, how: str) -> ChunkInfo:
    """Damage the second chunk; returns rosbags' index entry for it."""
    chunks, _ = _chunks(file)
    chunk = chunks[1]
    data = bytearray(file.read_bytes())
    at = chunk.chunk_start_offset + 9
    if how == "crc":  # a CRC (rosbags writes 0: none) that the records fail
        (name,) = struct.unpack_from("<I", data, at + 28)
        records = data[at + 40 + name : at + 40 + name + chunk.compressed_size]
        struct.pack_into("<I", data, at + 24, zlib.crc32(records) ^ 1)
    elif how == "compression":  # "zstd" → an unknown name of the same length
        assert data[at + 32 : at + 36] == b"zstd"
        data[at + 32 : at + 36] = b"zzzz"
    file.write_bytes(bytes(data))
    return chunk


@pytest.mark.parametrize("how", ["crc", "compression"])
def test_a_damaged_chunk_is_skipped_with_one_warning(tmp_path: Path, how: str) -> None:
    file = _apart(tmp_path, compressed=how == "compression")
    expected = _rosbags(file, {"/joint_states", "/robot_description"})
    chunk = _damage_chunk(file, how)
    kept = [m for m in expected if not chunk.message_start_time <= m[0] <= chunk.message_end_time]
    assert 0 < len(kept) < len(expected)
    warnings: list[str] = []
    with open_bag(file, warn=warnings.append) as bag:
        got = [
            (t, topic, bytes(d))
            for b in bag.blocks(["/joint_states", "/robot_description"])
            for t, topic, d in b.messages()
        ]
        assert got == kept
        assert len(warnings) == 1 and str(file) in warnings[0], warnings
        assert ("CRC" if how == "crc" else "unknown compression") in warnings[0]
        # read again (a run reads a bag in several passes): the chunk is not said twice
        assert [(t, bytes(d)) for t, d in bag.raw("/robot_description")] == [
            (t, d) for t, topic, d in kept if topic == "/robot_description"
        ]
    assert len(warnings) == 1, warnings


def test_a_cut_file_gives_a_prefix(tmp_path: Path) -> None:
    file = _intact(tmp_path, 20000)
    expected = _rosbags(file, {"/joint_states"})
    data = file.read_bytes()
    for fraction in (0.6, 0.95):
        cut = tmp_path / f"cut{fraction}.mcap"
        cut.write_bytes(data[: int(len(data) * fraction)])
        scan = McapScan(cut)
        got = _read(scan, ["/joint_states"])
        assert "breaks off" in scan.note and scan.chunks is not None  # the chunks its walk found
        assert scan.last("/joint_states") == (got[-1][0], got[-1][2])
        assert 0 < len(got) <= len(expected) and got == expected[: len(got)]
        assert fraction > 0.9 or len(got) < len(expected)  # the last 10 % are indexes and the summary


def test_junk_gives_nothing(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(os.urandom(2000))
    with pytest.raises(ValueError, match="not an MCAP file"):
        McapScan(junk)
    huge = tmp_path / "huge.mcap"  # a record claiming 2**63 bytes
    huge.write_bytes(b"\x89MCAP0\r\n" + b"\x06" + b"\xff" * 8 + b"\x00" * 50)
    scan = McapScan(huge)
    assert scan.topics == {} and scan.span is None and _read(scan, ["/joint_states"]) == []


def _mcap_string(text: str) -> bytes:
    return struct.pack("<I", len(text)) + text.encode()


def test_messages_outside_chunks_are_read_by_a_walk(tmp_path: Path) -> None:
    """A valid MCAP file whose messages are records of the data section itself (no chunks, no summary), laid out
    by hand from the spec: Header, Schema, Channel, Message records, Data End, a Footer with summary start 0."""
    definition = "string data"
    messages = [(T0 + 30, 1, string("c")), (T0 + 10, 1, string("a")), (T0 + 20, 2, joint_state(T0, ["j"], [1.5]))]
    records = [
        _record_bytes(0x01, _mcap_string("ros2") + _mcap_string("by hand")),
        _record_bytes(
            0x03,
            struct.pack("<H", 1)
            + _mcap_string("std_msgs/msg/String")
            + _mcap_string("ros2msg")
            + _mcap_string(definition),
        ),
        _record_bytes(
            0x03,
            struct.pack("<H", 2)
            + _mcap_string("sensor_msgs/msg/JointState")
            + _mcap_string("ros2msg")
            + _mcap_string(""),
        ),
        _record_bytes(
            0x04, struct.pack("<HH", 1, 1) + _mcap_string("/chatter") + _mcap_string("cdr") + struct.pack("<I", 0)
        ),
        _record_bytes(
            0x04, struct.pack("<HH", 2, 2) + _mcap_string("/joint_states") + _mcap_string("cdr") + struct.pack("<I", 0)
        ),
        *(_record_bytes(0x05, struct.pack("<HIQQ", c, k, t, t) + d) for k, (t, c, d) in enumerate(messages)),
        _record_bytes(0x0F, struct.pack("<I", 0)),
        _record_bytes(0x02, struct.pack("<QQI", 0, 0, 0)),
    ]
    file = tmp_path / "loose.mcap"
    file.write_bytes(b"\x89MCAP0\r\n" + b"".join(records) + b"\x89MCAP0\r\n")
    scan = McapScan(file)
    assert scan.note == "" and scan.chunks is None and scan.span == (T0 + 10, T0 + 30)
    assert {t: (i.msgtype, i.count, i.definition) for t, i in scan.topics.items()} == {
        "/chatter": ("std_msgs/msg/String", 2, definition),
        "/joint_states": ("sensor_msgs/msg/JointState", 1, ""),
    }
    assert _read(scan, ["/chatter", "/joint_states"]) == [
        (T0 + 10, "/chatter", string("a")),
        (T0 + 20, "/joint_states", joint_state(T0, ["j"], [1.5])),
        (T0 + 30, "/chatter", string("c")),
    ]
    assert _read(scan, ["/chatter"], start_ns=T0 + 11) == [(T0 + 30, "/chatter", string("c"))]
    assert scan.last("/chatter") == (T0 + 30, string("c"))
    assert scan.last("/chatter", before_ns=T0 + 30) == (T0 + 10, string("a"))


def _record_bytes(op: int, body: bytes) -> bytes:
    return bytes([op]) + struct.pack("<Q", len(body)) + body


def _copied_while(read: Callable[[], list[Message]]) -> tuple[list[Message], int]:
    """What ``read`` returns, and the most memory Python allocated beside it (tracemalloc: bytes objects and numpy
    buffers alike), less the messages it returns (their ``bytes``, made by the test)."""
    tracemalloc.start()
    try:
        got = read()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return got, peak


def test_a_filtered_out_message_costs_its_index_entry_not_its_bytes(tmp_path: Path) -> None:
    """Issue 38: on rosbag2's default, uncompressed chunks, a topic read alone must not copy the chunks' other
    messages. Two bags by rosbags (uncompressed chunks): chunks that overlap in time (merged into one block) and
    chunks that do not (each a view of the file's pages). Reading the small topic allocates a few kB, not the
    megabytes of 600 kB strings beside it in the same chunks; what comes out is what rosbags' reader gives."""
    spec = BagSpec(types={**TYPES, "/pad": "std_msgs/msg/String"})
    pad = string("p" * 600_000)
    spec.add("/robot_description", T0 + 10, string("first")).add("/pad", T0 + 100, pad).add("/pad", T0 + 100, pad)
    spec.add("/pad", T0 + 50, pad).add("/robot_description", T0 + 80, string("later")).add("/pad", T0 + 90, pad)
    overlap = storage_file(write_bag(tmp_path / "overlap", spec))
    chunks, _ = _chunks(overlap)
    assert [(c.message_start_time - T0, c.message_end_time - T0) for c in chunks[:2]] == [(10, 100), (50, 90)]
    assert {c.compression for c in chunks} == {""}  # rosbags' default: uncompressed chunks
    for file, topic in ((overlap, "/robot_description"), (_mixed(tmp_path), "/tf")):
        scan = McapScan(file)
        got, peak = _copied_while(lambda s=scan, t=topic: _read(s, [t]))  # type: ignore[misc]
        assert got == _rosbags(file, {topic})
        wanted = sum(len(d) for _, _, d in got)
        assert peak < 2 * wanted + 256_000, (file.name, peak, wanted)  # the file's chunks: > 2.4 MB each bag
        assert sum(c.chunk_length for c in _chunks(file)[0]) > 2_000_000
        for block in scan.blocks([topic]):  # each block: views of the file's pages, or a copy of its own messages
            assert block.buffer.obj is scan._map or len(block.buffer) == block.nbytes
        scan.close()


def test_a_topic_read_alone_does_not_read_its_chunks_for_their_crc(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Issue 38: rosbag2's recorder (the mcap library) writes each chunk's CRC, which covers all its records: checking
    it reads every byte of the chunk, the messages filtered out too. rosbags' bag (uncompressed chunks, CRC 0) given
    the CRCs the spec defines (CRC-32 of the chunk's records, zlib's): /tf alone is read without computing one, the
    three topics with one per chunk, over the whole chunk; the messages are rosbags' reader's either way."""
    import r2d2_viz.sources.bags.mcap_records as mcap_records

    file = _mixed(tmp_path)
    chunks, _ = _chunks(file)
    data = bytearray(file.read_bytes())
    for c in chunks:  # spec: Chunk = op, length, start, end, uncompressed size, uncompressed crc u32, compression, ...
        at = c.chunk_start_offset + 9
        (name,) = struct.unpack_from("<I", data, at + 28)
        assert name == 0  # uncompressed
        records = data[at + 40 : at + 40 + c.compressed_size]
        struct.pack_into("<I", data, at + 24, zlib.crc32(records))
    file.write_bytes(bytes(data))
    checked: list[int] = []

    def crc32(buffer: memoryview) -> int:
        checked.append(len(buffer))
        return zlib.crc32(buffer)

    monkeypatch.setattr(mcap_records, "zlib", type("Zlib", (), {"crc32": staticmethod(crc32)}))
    scan = McapScan(file)
    assert _read(scan, ["/tf"]) == _rosbags(file, {"/tf"}) and checked == []
    topics = ["/joint_states", "/tf", "/robot_description"]
    assert _read(scan, topics) == _rosbags(file, set(topics)) and scan.problems == {}
    assert sorted(checked) == sorted(c.uncompressed_size for c in chunks) and len(chunks) > 3


@pytest.mark.parametrize("compressed", [False, True])
def test_a_topic_written_after_the_others_is_merged_in_flight(tmp_path: Path, compressed: bool) -> None:
    """Issue 38 (``--video`` on a camera bag with an H.264 topic: 1 GB): a bag written topic by topic, as converting
    tools write — 30 strings of 600 kB (two a chunk), then 30 small messages at the same times (one chunk spanning
    them all): every chunk overlaps the last in time. Reading both topics, each block dropped before the next, holds
    the chunks in flight (tracemalloc: a few MB), not the whole file merged at once (18 MB); the messages are
    rosbags' reader's, in time order. Uncompressed chunks (rosbags' default) and zstd ones; the uncompressed strings
    are not even copied (each a run of its own between the small messages)."""
    spec = BagSpec(types={"/pad": "std_msgs/msg/String", "/small": "std_msgs/msg/String"})
    for k in range(30):
        spec.add("/pad", T0 + k * MS, string(chr(65 + k % 26) * 600_000))
    for k in range(30):
        spec.add("/small", T0 + k * MS + 1, string(f"small {k}"))
    path = tmp_path / "sequential"
    if compressed:
        writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        writer.open()
        connections = {t: writer.add_connection(t, spec.types[t], typestore=TS) for t in spec.types}
        for topic, t, data in spec.messages:
            writer.write(connections[topic], t, data)
        writer.close()
        file = storage_file(path)
    else:
        file = storage_file(write_bag(path, spec))
    chunks, channels = _chunks(file)
    small = [c for c in chunks if set(c.message_index_offsets) == {k for k, t in channels.items() if t == "/small"}]
    assert len(small) == 1 and (small[0].message_start_time, small[0].message_end_time) == (T0 + 1, T0 + 29 * MS + 1)
    assert len(chunks) == 16

    scan, got, peaks = McapScan(file), [], []
    tracemalloc.start()
    try:
        for block in scan.blocks(["/pad", "/small"]):  # each block dropped before the next is read
            peaks.append(tracemalloc.get_traced_memory()[1] - sum(len(d) for _, _, d in got))  # less what is kept
            got += [(t, topic, bytes(d)) for t, topic, d in block.messages()]
            del block
            tracemalloc.reset_peak()
    finally:
        tracemalloc.stop()
    assert got == _rosbags(file, {"/pad", "/small"})
    assert [t for t, _, _ in got] == sorted(t for _, t, _ in spec.messages)
    assert max(peaks) < 5_000_000, peaks  # a chunk or two (1.2 MB each) and the step being merged, not 18 MB
    if not compressed:  # the strings' runs between the small messages: views of the file's pages, never copied
        assert all(block.buffer.obj is scan._map for block in scan.blocks(["/pad", "/small"]))
