"""MCAP records as the spec lays them out (https://mcap.dev/spec): opcodes, the record walk, strings, the chunk
index, and a chunk's messages walked record by record into a :class:`~r2d2_viz.sources.bags.storage.Block`; blocks of
chunks that overlap in time merged in time order. What :mod:`.mcap_scan` reads a file with. Pure: no rerun import.
"""

from __future__ import annotations

import itertools
import mmap
import struct
import sys
import zlib
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from types import ModuleType
from typing import NamedTuple, TypeVar

import numpy as np

from r2d2_viz.sources.bags.storage import Block, in_time_order

C = TypeVar("C")


def _zstd() -> ModuleType:
    """zstd, imported when a chunk needs it (a run without a bag imports neither codec)."""
    if sys.version_info >= (3, 14):  # pragma: no cover
        from compression import zstd
    else:
        from backports import zstd
    return zstd


def _zstd_decompress(raw: memoryview, size: int) -> bytes:
    """A zstd chunk decompressed into a buffer of the size it announces (1.7× faster than ``zstd.decompress``, which
    grows its buffer as it goes); several frames, or more data than announced, through ``zstd.decompress``."""
    zstd = _zstd()
    decompressor = zstd.ZstdDecompressor()
    out: bytes = decompressor.decompress(raw, max_length=size)
    if not decompressor.eof or decompressor.unused_data:
        out = zstd.decompress(raw)
    return out


MAGIC = b"\x89MCAP0\r\n"
OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = 0x02, 0x03, 0x04, 0x05, 0x06
OP_MESSAGE_INDEX, OP_CHUNK_INDEX, OP_STATISTICS, OP_DATA_END = 0x07, 0x08, 0x0B, 0x0F
U16, U32, U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
MESSAGE = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time
HEAD = 9 + MESSAGE.size  # a message record's bytes before its data


class BrokenError(Exception):
    """The file ends or is damaged here."""


READ_ERRORS = (BrokenError, struct.error, IndexError, ValueError, RuntimeError, OverflowError, MemoryError)
"""What reading a damaged record or chunk raises (the codecs raise ``RuntimeError`` / ``ValueError``)."""


def string_at(buf: bytes | mmap.mmap | memoryview, at: int) -> tuple[str, int]:
    (n,) = U32.unpack_from(buf, at)
    end = at + 4 + n
    if end > len(buf):
        raise BrokenError("a string runs past its record")
    return bytes(buf[at + 4 : end]).decode("utf-8", "replace"), end


class Channel(NamedTuple):
    id: int
    topic: str
    schema_id: int


@dataclass(frozen=True)
class Schema:
    name: str
    encoding: str
    data: str


@dataclass(frozen=True)
class ChunkIndex:
    start_ns: int
    end_ns: int
    offset: int
    length: int
    index_offsets: dict[int, int]
    """channel id → file offset of its message index record for this chunk."""
    channels: frozenset[int] = frozenset()
    """The channels it holds, where a scan found them (a file without a summary: no message indexes)."""


def schema_at(buf: bytes | mmap.mmap | memoryview, at: int) -> tuple[int, Schema]:
    """A Schema record's body: its id and the schema."""
    (schema_id,) = U16.unpack_from(buf, at)
    name, at = string_at(buf, at + 2)
    encoding, at = string_at(buf, at)
    data, _ = string_at(buf, at)
    return schema_id, Schema(name, encoding, data)


def channel_at(buf: bytes | mmap.mmap | memoryview, at: int) -> tuple[int, Channel]:
    """A Channel record's body: its id and the channel."""
    channel_id, schema_id = struct.unpack_from("<HH", buf, at)
    topic, _ = string_at(buf, at + 4)
    return channel_id, Channel(channel_id, topic, schema_id)


def walk_records(buf: mmap.mmap | memoryview, at: int, end: int) -> Iterator[tuple[int, int, int]]:
    """``(op, body start, body end)`` of the records from ``at`` up to ``end``."""
    while at + 9 <= end:
        op = buf[at]
        (size,) = U64.unpack_from(buf, at + 1)
        body, at = at + 9, at + 9 + size
        if at > end:
            raise BrokenError("a record runs past the end of the file")
        yield op, body, at


def holds(c: ChunkIndex, wanted: dict[int, int]) -> bool:
    """Whether the chunk holds messages of a wanted channel (a chunk index without message index offsets may)."""
    found = c.index_offsets or c.channels
    return not found or not wanted.keys().isdisjoint(found)


def chunk_index(buf: mmap.mmap, at: int, stop: int, size: int) -> ChunkIndex:
    start_ns, end_ns, offset, length = struct.unpack_from("<QQQQ", buf, at)
    (n,) = U32.unpack_from(buf, at + 32)
    if at + 36 + n > stop or n % 10:
        raise BrokenError("a chunk index runs past its record")
    pairs = np.frombuffer(buf, dtype=np.dtype([("id", "<u2"), ("at", "<u8")]), count=n // 10, offset=at + 36)
    offsets = {int(c): int(k) for c, k in zip(pairs["id"], pairs["at"], strict=True)}
    if offset + length > size:
        raise BrokenError("a chunk index points past the end of the file")
    return ChunkIndex(start_ns, end_ns, offset, length, offsets)


def index_counts(buf: mmap.mmap, c: ChunkIndex) -> dict[int, int] | None:
    """Messages per channel in a chunk, from the lengths of its message index records (None: one is unusable)."""
    counts: dict[int, int] = {}
    for channel_id, at in c.index_offsets.items():
        if at + 15 > len(buf) or buf[at] != OP_MESSAGE_INDEX:
            return None
        (n,) = U32.unpack_from(buf, at + 11)
        if n % 16:
            return None
        counts[channel_id] = n // 16
    return counts


def message_times(data: memoryview, start: int, end: int) -> Iterator[tuple[int, int]]:
    for op, at, _ in walk_records(data, start, end):
        if op == OP_MESSAGE:
            channel_id, _, log_time, _ = MESSAGE.unpack_from(data, at)
            yield channel_id, log_time


def walk_messages(data: memoryview, order: tuple[str, ...], wanted: dict[int, int]) -> Block:
    """The wanted messages of a chunk's records, record by record (a chunk without message indexes)."""
    times: list[int] = []
    starts: list[int] = []
    lengths: list[int] = []
    index: list[int] = []
    unpack, head = U64.unpack_from, MESSAGE.unpack_from
    at, end = 0, len(data)
    while at + 9 <= end:
        op, (size,) = data[at], unpack(data, at + 1)
        body, at = at + 9, at + 9 + size
        if at > end:
            raise BrokenError("a record runs past its chunk")
        if op == OP_MESSAGE:
            channel_id, _, log_time, _ = head(data, body)
            k = wanted.get(channel_id)
            if k is not None:
                times.append(log_time)
                starts.append(body + MESSAGE.size)
                lengths.append(size - MESSAGE.size)
                index.append(k)
    return Block(
        np.asarray(times, dtype=np.int64),
        np.asarray(index, dtype=np.int32),
        order,
        data,
        np.asarray(starts, dtype=np.int64),
        np.asarray(lengths, dtype=np.int64),
    )


def overlapping(chunks: list[ChunkIndex]) -> Iterator[list[ChunkIndex]]:
    """Chunks (sorted by start) grouped where their time ranges overlap: each group merged (:func:`merged_chunks`)."""
    group: list[ChunkIndex] = []
    end = -1
    for c in chunks:
        if group and c.start_ns > end:
            yield group
            group = []
        group.append(c)
        end = max(end, c.end_ns)
    if group:
        yield group


def merged_chunks(
    cluster: Sequence[C], read: Callable[[C], Block | None], place: Callable[[C], tuple[int, int]]
) -> Iterator[Block]:
    """The messages of chunks that overlap in time (``read`` gives a chunk's wanted messages, in time order) as
    time-ordered blocks, holding only the chunks in flight: a chunk is read when the merge reaches its start, and
    each step gives every message up to the earliest of the open chunks' last times and the next chunk's start.
    A topic written after the others (its few chunks spanning the whole file) keeps one of its chunks open beside
    the others', instead of the whole file merged at once. Messages received at one time keep the file's order.
    ``place``: a chunk's first receive time and its place in the file (any storage's chunks: MCAP, ROS 1)."""
    pending = deque(sorted(cluster, key=place))
    live: list[tuple[int, Block, int]] = []  # (file offset, block, its first message not given yet)
    while pending or live:
        head = min((int(b.times_ns[at]) for _, b, at in live), default=None)
        if pending and (head is None or place(pending[0])[0] <= head):
            c = pending.popleft()
            block = read(c)
            if block is not None and len(block):
                live = sorted([*live, (place(c)[1], block, 0)], key=lambda x: x[0])
            continue
        cutoff = min(int(b.times_ns[-1]) for _, b, _ in live)
        if pending:
            cutoff = min(cutoff, place(pending[0])[0] - 1)
        parts, kept = [], []
        for offset, block, at in live:
            end = at + int(np.searchsorted(block.times_ns[at:], cutoff, side="right"))
            if end > at:
                parts.append(block if at == 0 and end == len(block) else _share(block, block.take(np.arange(at, end))))
            if end < len(block):
                kept.append((offset, block, end))
        live = kept
        yield from _in_order(parts)


def _share(block: Block, piece: Block) -> Block:
    """``piece`` of ``block`` counted as its share (by bytes) of what reading ``block`` took."""
    if not block.read_nbytes:
        return piece
    return replace(piece, read_nbytes=block.read_nbytes * piece.nbytes // max(block.nbytes, 1))


RUN_BYTES = 64 << 10
"""Interleaved parts whose runs (messages in a row from one part) hold this many bytes on average are given run by
run, as views of their chunks (a camera's frames between a video topic's samples: not copied); smaller runs are
merged into one block (copying a few small messages costs less than a block each)."""


def _in_order(parts: list[Block]) -> Iterator[Block]:
    """Parts (in file order) as time-ordered blocks: as they are where one ends before the next starts, run by run
    where their runs are big (:data:`RUN_BYTES`), else merged (:func:`merge_blocks`)."""
    ordered = sorted(parts, key=lambda p: int(p.times_ns[0]))
    if all(int(a.times_ns[-1]) < int(b.times_ns[0]) for a, b in itertools.pairwise(ordered)):
        yield from ordered
        return
    order = np.argsort(np.concatenate([p.times_ns for p in parts]), kind="stable")  # ties: the file's order
    part = np.repeat(np.arange(len(parts)), [len(p) for p in parts])[order]
    edges = np.flatnonzero(np.diff(part)) + 1
    if sum(p.nbytes for p in parts) < RUN_BYTES * (len(edges) + 1):
        yield merge_blocks(parts)
        return
    firsts = np.cumsum([0] + [len(p) for p in parts[:-1]])
    for run in np.split(order, edges):
        k = int(np.searchsorted(firsts, run[0], side="right")) - 1
        yield _share(parts[k], parts[k].take(run - firsts[k]))


def merge_blocks(parts: list[Block]) -> Block:
    """Blocks of overlapping chunks as one block in time order: their messages' bytes copied into one buffer, and
    only theirs (a chunk's other messages, filtered out, are neither read nor copied)."""
    lengths = np.concatenate([p.lengths for p in parts])
    starts = np.zeros(len(lengths), dtype=np.int64)
    np.cumsum(lengths[:-1], out=starts[1:])
    pieces = (p.buffer[a : a + n] for p in parts for a, n in zip(p.starts.tolist(), p.lengths.tolist(), strict=True))
    block = Block(
        np.concatenate([p.times_ns for p in parts]),
        np.concatenate([p.topic_index for p in parts]),
        parts[0].topics,
        memoryview(b"".join(pieces)),
        starts,
        lengths,
        sum(p.cost for p in parts),
        seq=None
        if all(p.seq is None for p in parts)
        else np.concatenate([np.full(len(p), -1, np.int64) if p.seq is None else p.seq for p in parts]),
        sizes=None if all(p.sizes is None for p in parts) else np.concatenate([p.stored_lengths for p in parts]),
    )
    return in_time_order(block)


def statistics(buf: mmap.mmap, at: int, stop: int) -> tuple[tuple[int, int] | None, dict[int, int]]:
    """A Statistics record: the span of the messages (None: none) and the message count of each channel."""
    (message_count,) = U64.unpack_from(buf, at)
    first, last = struct.unpack_from("<QQ", buf, at + 26)
    (n,) = U32.unpack_from(buf, at + 42)
    if at + 46 + n > stop:
        raise BrokenError("statistics run past their record")
    pairs = np.frombuffer(buf, dtype=np.dtype([("id", "<u2"), ("n", "<u8")]), count=n // 10, offset=at + 46)
    counts = {int(c): int(k) for c, k in zip(pairs["id"], pairs["n"], strict=True)}
    return ((first, last) if message_count else None), counts


def chunk_record(buf: mmap.mmap, start: int, end: int) -> tuple[int, int, str, memoryview]:
    """A chunk record's uncompressed size, CRC, compression and its (compressed) records' bytes, checked to lie
    within the record."""
    if end > len(buf) or start + 9 > end or buf[start] != OP_CHUNK:
        raise BrokenError("a chunk index points past the end or at no chunk")
    at = start + 9
    _, _, uncompressed_size, crc = struct.unpack_from("<QQQI", buf, at)
    compression, at = string_at(buf, at + 28)
    (size,) = U64.unpack_from(buf, at)
    if at + 8 + size > end:
        raise BrokenError("a chunk runs past its record")
    return uncompressed_size, crc, compression, memoryview(buf)[at + 8 : at + 8 + size]


def chunk_data(buf: mmap.mmap, start: int, end: int, *, part: bool = False) -> memoryview:
    """A chunk record's messages, decompressed and checked. ``part``: only some of its messages are wanted — an
    uncompressed chunk is then not checked against its CRC, which would read every byte of it (its other messages'
    pages never touched); a compressed one, decompressed whole anyway, still is."""
    uncompressed_size, crc, compression, raw = chunk_record(buf, start, end)
    if compression == "lz4":
        from lz4.frame import decompress as lz4_decompress

        data: memoryview = memoryview(lz4_decompress(raw))
    elif compression == "zstd":
        data = memoryview(_zstd_decompress(raw, uncompressed_size))
    elif compression:
        raise BrokenError(f"a chunk has an unknown compression ({compression[:20]!r})")
    else:
        data = raw
    if len(data) != uncompressed_size:
        raise BrokenError("a chunk's size is not what it says")
    if crc and (compression or not part) and zlib.crc32(data) != crc:
        raise BrokenError("a chunk fails its CRC check")
    return data


def indexed(
    buf: mmap.mmap, c: ChunkIndex, order: tuple[str, ...], wanted: dict[int, int], data: memoryview
) -> Block | None:
    """The wanted messages from the chunk's message indexes, vectorised (None: no usable index)."""
    size = len(data)
    times, offsets, topic_index = [], [], []
    for channel_id, k in wanted.items():
        at = c.index_offsets.get(channel_id)
        if at is None:
            continue
        if at + 15 > len(buf) or buf[at] != OP_MESSAGE_INDEX:
            return None
        (n,) = U32.unpack_from(buf, at + 11)
        if at + 15 + n > len(buf) or n % 16:
            return None
        pairs = np.frombuffer(buf, dtype="<u8", count=n // 8, offset=at + 15).reshape(-1, 2)
        times.append(pairs[:, 0].astype(np.int64))
        offsets.append(pairs[:, 1].astype(np.int64))
        topic_index.append(np.full(len(pairs), k, dtype=np.int32))
    if not times:
        return None
    t, off, ti = np.concatenate(times), np.concatenate(offsets), np.concatenate(topic_index)
    if len(off) and (off.min() < 0 or off.max() + HEAD > size):
        return None
    raw = np.frombuffer(data, dtype=np.uint8)
    ops = raw[off] if len(off) else off
    lengths = raw[off[:, None] + np.arange(1, 9)].copy().view("<u8").ravel().astype(np.int64) if len(off) else off
    bad = np.any(ops != OP_MESSAGE) or np.any(lengths < MESSAGE.size) or np.any(off + 9 + lengths > size)
    if len(off) and bad:
        return None
    rows = np.lexsort((off, t))
    t, off, ti, lengths = t[rows], off[rows], ti[rows], lengths[rows]
    return Block(t, ti, order, data, off + HEAD, lengths - MESSAGE.size)
