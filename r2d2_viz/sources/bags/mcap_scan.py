"""An MCAP file as a :class:`~r2d2_viz.sources.bags.storage.Storage`, read through its own index where it has one
(summary: channels, schemas, statistics, one chunk index per chunk; each chunk's message indexes): chunks that hold
none of the wanted topics, or lie outside the time asked for, are never read, and a chunk's wanted messages are
found from its message indexes as numpy arrays, not record by record. A file without a summary (a recorder that was
killed leaves none) is read from the start, record by record, up to the first damage. The file is memory-mapped:
uncompressed chunks are handed on as views of the file's pages, not copies. MCAP: https://mcap.dev/spec; lz4 and zstd
come with ``rosbags``.

A damaged chunk (bad CRC, unknown compression, an index pointing past the end) is skipped and counted in
:attr:`McapScan.problems`; the bag says it once. Measured against the ``mcap`` library (the format's reference
reader) in ``benchmarks/mcap_readers.py``. Pure: no rerun import.
"""

from __future__ import annotations

import mmap
import struct
import sys
import zlib
from collections.abc import Collection, Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import NamedTuple

import numpy as np

from r2d2_viz.sources.bags.storage import Block, TopicInfo, in_time_order, topic_tuple


def _zstd() -> ModuleType:
    """zstd, imported when a chunk needs it (a run without a bag imports neither codec)."""
    if sys.version_info >= (3, 14):  # pragma: no cover
        from compression import zstd
    else:
        from backports import zstd
    return zstd


MAGIC = b"\x89MCAP0\r\n"
_OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE, _OP_CHUNK = 0x02, 0x03, 0x04, 0x05, 0x06
_OP_MESSAGE_INDEX, _OP_CHUNK_INDEX, _OP_STATISTICS, _OP_DATA_END = 0x07, 0x08, 0x0B, 0x0F
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
_MESSAGE = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time
_HEAD = 9 + _MESSAGE.size  # a message record's bytes before its data


class BrokenError(Exception):
    """The file ends or is damaged here."""


def _string(buf: bytes | mmap.mmap | memoryview, at: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(buf, at)
    end = at + 4 + n
    if end > len(buf):
        raise BrokenError("a string runs past its record")
    return bytes(buf[at + 4 : end]).decode("utf-8", "replace"), end


class _Channel(NamedTuple):
    id: int
    topic: str
    schema_id: int


@dataclass(frozen=True)
class _Schema:
    name: str
    encoding: str
    data: str


@dataclass(frozen=True)
class _ChunkIndex:
    start_ns: int
    end_ns: int
    offset: int
    length: int
    index_offsets: dict[int, int]
    """channel id → file offset of its message index record for this chunk."""


def _records(buf: mmap.mmap | memoryview, at: int, end: int) -> Iterator[tuple[int, int, int]]:
    """``(op, body start, body end)`` of the records from ``at`` up to ``end``."""
    while at + 9 <= end:
        op = buf[at]
        (size,) = _U64.unpack_from(buf, at + 1)
        body, at = at + 9, at + 9 + size
        if at > end:
            raise BrokenError("a record runs past the end of the file")
        yield op, body, at


class McapScan:
    """One MCAP storage file (see the module docstring); raises ``ValueError`` when it is not MCAP at all."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.note = ""
        self.problems: dict[str, int] = {}
        """Damage met while reading (kind → chunks skipped); the bag says it and clears it."""
        self._damaged: set[int] = set()
        """File offsets of the chunks found damaged (not read again)."""
        self.channels: dict[int, _Channel] = {}
        self.schemas: dict[int, _Schema] = {}
        self.chunks: list[_ChunkIndex] | None = None
        """The chunk index (None: the file has no usable summary and is read from the start)."""
        self._counts: dict[int, int] = {}
        self._span: tuple[int, int] | None = None
        with path.open("rb") as f:
            size = f.seek(0, 2)
            if size < len(MAGIC):
                raise ValueError("not an MCAP file (too short)")
            self._map = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        if self._map[: len(MAGIC)] != MAGIC:
            raise ValueError("not an MCAP file (no magic)")
        if not self._read_summary():
            self._scan_everything()
        self.topics = self._topics()

    # --- the summary --------------------------------------------------------------------------------------------

    def _read_summary(self) -> bool:
        """Channels, schemas, counts and chunk indexes from the summary; False when the file has none usable."""
        buf, size = self._map, len(self._map)
        footer = size - len(MAGIC) - 29
        if footer < len(MAGIC) or buf[size - len(MAGIC) :] != MAGIC or buf[footer] != _OP_FOOTER:
            self.note = "the file breaks off (no footer, no index)"
            return False
        summary_start, offsets_start, _ = struct.unpack_from("<QQI", buf, footer + 9)
        if summary_start == 0:
            return False  # a valid file without a summary: read from the start, no warning
        end = offsets_start or footer
        if not len(MAGIC) <= summary_start <= end <= footer:
            self.note = "its summary points outside the file"
            return False
        chunks: list[_ChunkIndex] = []
        try:
            for op, at, stop in _records(buf, summary_start, end):
                if op == _OP_SCHEMA:
                    self._schema(buf, at)
                elif op == _OP_CHANNEL:
                    self._channel(buf, at)
                elif op == _OP_CHUNK_INDEX:
                    chunks.append(_chunk_index(buf, at, stop, size))
                elif op == _OP_STATISTICS:
                    self._statistics(buf, at, stop)
        except (BrokenError, struct.error, IndexError) as exc:
            self.note = f"its summary is damaged ({exc or type(exc).__name__})"
            self.channels, self.schemas, self._counts = {}, {}, {}
            return False
        if not chunks and self._counts and sum(self._counts.values()):
            return False  # messages outside chunks: only a scan finds them
        self.chunks = sorted(chunks, key=lambda c: (c.start_ns, c.offset))
        if chunks and self._span is None:
            self._span = (min(c.start_ns for c in chunks), max(c.end_ns for c in chunks))
        return True

    def _schema(self, buf: mmap.mmap | memoryview, at: int) -> None:
        (schema_id,) = _U16.unpack_from(buf, at)
        name, at = _string(buf, at + 2)
        encoding, at = _string(buf, at)
        data, _ = _string(buf, at)
        self.schemas[schema_id] = _Schema(name, encoding, data)

    def _channel(self, buf: mmap.mmap | memoryview, at: int) -> None:
        channel_id, schema_id = struct.unpack_from("<HH", buf, at)
        topic, _ = _string(buf, at + 4)
        self.channels[channel_id] = _Channel(channel_id, topic, schema_id)

    def _statistics(self, buf: mmap.mmap, at: int, stop: int) -> None:
        (message_count,) = _U64.unpack_from(buf, at)
        first, last = struct.unpack_from("<QQ", buf, at + 26)
        if message_count:
            self._span = (first, last)
        (n,) = _U32.unpack_from(buf, at + 42)
        if at + 46 + n > stop:
            raise BrokenError("statistics run past their record")
        pairs = np.frombuffer(buf, dtype=np.dtype([("id", "<u2"), ("n", "<u8")]), count=n // 10, offset=at + 46)
        self._counts = {int(c): int(k) for c, k in zip(pairs["id"], pairs["n"], strict=True)}

    def _topics(self) -> dict[str, TopicInfo]:
        topics: dict[str, TopicInfo] = {}
        for channel in self.channels.values():
            schema = self.schemas.get(channel.schema_id, _Schema("", "", ""))
            old = topics.get(channel.topic)
            count = (old.count if old else 0) + self._counts.get(channel.id, 0)
            topics[channel.topic] = TopicInfo(channel.topic, schema.name, count, schema.data, schema.encoding)
        return topics

    # --- reading ------------------------------------------------------------------------------------------------

    @property
    def span(self) -> tuple[int, int] | None:
        return self._span

    def _wanted(self, topics: Collection[str]) -> dict[int, int]:
        """channel id → its topic's index in :func:`topic_tuple` order."""
        order = topic_tuple(topics)
        return {c.id: order.index(c.topic) for c in self.channels.values() if c.topic in order}

    def blocks(
        self, topics: Collection[str], *, start_ns: int | None = None, stop_ns: int | None = None
    ) -> Iterator[Block]:
        order = topic_tuple(topics)
        wanted = self._wanted(order)
        if self.chunks is None:
            yield from self._scan_blocks(order, wanted, start_ns, stop_ns)
            return
        lo = -1 if start_ns is None else start_ns
        hi = 2**64 if stop_ns is None else stop_ns
        chosen = [c for c in self.chunks if c.end_ns >= lo and c.start_ns < hi and _holds(c, wanted)]
        for cluster in _clusters(chosen):
            parts = [b for c in cluster if (b := self._chunk_block(c, order, wanted, lo, hi)) is not None]
            if len(parts) == 1:
                yield parts[0]
            elif parts:
                yield _merged(parts)

    def _chunk_block(
        self, c: _ChunkIndex, order: tuple[str, ...], wanted: dict[int, int], lo: int, hi: int
    ) -> Block | None:
        """The wanted messages of one chunk; a damaged chunk is counted in :attr:`problems` (once) and skipped."""
        if c.offset in self._damaged:
            return None
        try:
            data = self._chunk_data(c.offset, c.offset + c.length)
            found = self._indexed(c, order, wanted, data)
            block = found if found is not None else _walk(data, order, wanted)
        except (BrokenError, struct.error, IndexError, ValueError, RuntimeError, OverflowError, MemoryError) as exc:
            kind = str(exc) if isinstance(exc, BrokenError) else f"cannot read ({type(exc).__name__})"
            self.problems[kind] = self.problems.get(kind, 0) + 1
            self._damaged.add(c.offset)
            return None
        keep = (block.times_ns >= lo) & (block.times_ns < hi)
        block = block if keep.all() else block.take(np.flatnonzero(keep))
        return in_time_order(block) if len(block) else None

    def _chunk_data(self, start: int, end: int) -> memoryview:
        """A chunk record's messages, decompressed and checked."""
        buf = self._map
        if end > len(buf) or start + 9 > end or buf[start] != _OP_CHUNK:
            raise BrokenError("a chunk index points past the end or at no chunk")
        at = start + 9
        _, _, uncompressed_size, crc = struct.unpack_from("<QQQI", buf, at)
        compression, at = _string(buf, at + 28)
        (size,) = _U64.unpack_from(buf, at)
        if at + 8 + size > end:
            raise BrokenError("a chunk runs past its record")
        raw = memoryview(buf)[at + 8 : at + 8 + size]
        if compression == "lz4":
            from lz4.frame import decompress as lz4_decompress

            data: memoryview = memoryview(lz4_decompress(raw))
        elif compression == "zstd":
            data = memoryview(_zstd().decompress(raw))
        elif compression:
            raise BrokenError(f"a chunk has an unknown compression ({compression[:20]!r})")
        else:
            data = raw
        if len(data) != uncompressed_size:
            raise BrokenError("a chunk's size is not what it says")
        if crc and zlib.crc32(data) != crc:
            raise BrokenError("a chunk fails its CRC check")
        return data

    def _indexed(
        self, c: _ChunkIndex, order: tuple[str, ...], wanted: dict[int, int], data: memoryview
    ) -> Block | None:
        """The wanted messages from the chunk's message indexes, vectorised (None: no usable index)."""
        buf, size = self._map, len(data)
        times, offsets, topic_index = [], [], []
        for channel_id, k in wanted.items():
            at = c.index_offsets.get(channel_id)
            if at is None:
                continue
            if at + 15 > len(buf) or buf[at] != _OP_MESSAGE_INDEX:
                return None
            (n,) = _U32.unpack_from(buf, at + 11)
            if at + 15 + n > len(buf) or n % 16:
                return None
            pairs = np.frombuffer(buf, dtype="<u8", count=n // 8, offset=at + 15).reshape(-1, 2)
            times.append(pairs[:, 0].astype(np.int64))
            offsets.append(pairs[:, 1].astype(np.int64))
            topic_index.append(np.full(len(pairs), k, dtype=np.int32))
        if not times:
            return None
        t, off, ti = np.concatenate(times), np.concatenate(offsets), np.concatenate(topic_index)
        if len(off) and (off.min() < 0 or off.max() + _HEAD > size):
            return None
        raw = np.frombuffer(data, dtype=np.uint8)
        ops = raw[off] if len(off) else off
        lengths = raw[off[:, None] + np.arange(1, 9)].copy().view("<u8").ravel().astype(np.int64) if len(off) else off
        bad = np.any(ops != _OP_MESSAGE) or np.any(lengths < _MESSAGE.size) or np.any(off + 9 + lengths > size)
        if len(off) and bad:
            return None
        rows = np.lexsort((off, t))
        t, off, ti, lengths = t[rows], off[rows], ti[rows], lengths[rows]
        return Block(t, ti, order, data, off + _HEAD, lengths - _MESSAGE.size)

    # --- files without a summary ----------------------------------------------------------------------------------

    def _scan_everything(self) -> None:
        """Channels, schemas, counts and span of a file without a summary: one walk up to its first damage."""
        first, last, total = 2**64, -1, 0
        for op, _, body, start, end in self._walk_file():
            if op != _OP_CHUNK:
                continue
            for channel_id, t in _message_times(body, start, end):
                self._counts[channel_id] = self._counts.get(channel_id, 0) + 1
                first, last, total = min(first, t), max(last, t), total + 1
        if total:
            self._span = (first, last)
        if self.note:
            self.note = f"{self.note}: recovered {total} messages"

    def _walk_file(self) -> Iterator[tuple[int, int, memoryview, int, int]]:
        """``(op, file offset, buffer, start, end)`` of the data section's records — a chunk's decompressed
        records, or a record outside chunks — noting schemas and channels, until the file ends or breaks."""
        buf = self._map
        view = memoryview(buf)
        try:
            for op, at, stop in _records(buf, len(MAGIC), len(buf)):
                if op == _OP_DATA_END:
                    return
                if op == _OP_CHUNK:
                    data = self._chunk_data(at - 9, stop)
                    self._note_definitions(data, 0, len(data))
                    yield op, at - 9, data, 0, len(data)
                elif op in (_OP_SCHEMA, _OP_CHANNEL):
                    self._note_definitions(view, at - 9, stop)
                elif op == _OP_MESSAGE:
                    yield _OP_CHUNK, at - 9, view, at - 9, stop
        except (BrokenError, struct.error, IndexError, ValueError, RuntimeError, OverflowError, MemoryError) as exc:
            if not self.note:
                self.note = f"the file is damaged ({exc or type(exc).__name__})"

    def _note_definitions(self, data: memoryview, start: int, end: int) -> None:
        for op, at, _ in _records(data, start, end):
            if op == _OP_SCHEMA:
                self._schema(data, at)
            elif op == _OP_CHANNEL:
                self._channel(data, at)

    def _scan_blocks(
        self, order: tuple[str, ...], wanted: dict[int, int], start_ns: int | None, stop_ns: int | None
    ) -> Iterator[Block]:
        lo = -1 if start_ns is None else start_ns
        hi = 2**64 if stop_ns is None else stop_ns
        for _, _, data, start, end in self._walk_file():
            wanted = self._wanted(order)  # channels appear as the file goes on
            block = _walk(data[start:end], order, wanted)
            keep = (block.times_ns >= lo) & (block.times_ns < hi)
            if keep.any():
                yield in_time_order(block if keep.all() else block.take(np.flatnonzero(keep)))

    def last(self, topic: str, *, before_ns: int | None = None) -> tuple[int, bytes] | None:
        hi = 2**64 if before_ns is None else before_ns
        wanted = self._wanted([topic])
        if self.chunks is None:
            found = None
            for block in self.blocks([topic], stop_ns=hi):
                found = (int(block.times_ns[-1]), bytes(block.data(len(block) - 1)))
            return found
        for c in sorted(self.chunks, key=lambda c: c.end_ns, reverse=True):
            if c.start_ns >= hi or not _holds(c, wanted):
                continue
            part = self._chunk_block(c, (topic,), wanted, -1, hi)
            if part is not None:
                return int(part.times_ns[-1]), bytes(part.data(len(part) - 1))
        return None

    def close(self) -> None:
        try:
            self._map.close()
        except BufferError:  # blocks still hold views of the file's pages: the map closes when they are gone
            pass


def _holds(c: _ChunkIndex, wanted: dict[int, int]) -> bool:
    """Whether the chunk holds messages of a wanted channel (a chunk index without message index offsets may)."""
    return not c.index_offsets or not wanted.keys().isdisjoint(c.index_offsets)


def _chunk_index(buf: mmap.mmap, at: int, stop: int, size: int) -> _ChunkIndex:
    start_ns, end_ns, offset, length = struct.unpack_from("<QQQQ", buf, at)
    (n,) = _U32.unpack_from(buf, at + 32)
    if at + 36 + n > stop or n % 10:
        raise BrokenError("a chunk index runs past its record")
    pairs = np.frombuffer(buf, dtype=np.dtype([("id", "<u2"), ("at", "<u8")]), count=n // 10, offset=at + 36)
    offsets = {int(c): int(k) for c, k in zip(pairs["id"], pairs["at"], strict=True)}
    if offset + length > size:
        raise BrokenError("a chunk index points past the end of the file")
    return _ChunkIndex(start_ns, end_ns, offset, length, offsets)


def _message_times(data: memoryview, start: int, end: int) -> Iterator[tuple[int, int]]:
    for op, at, _ in _records(data, start, end):
        if op == _OP_MESSAGE:
            channel_id, _, log_time, _ = _MESSAGE.unpack_from(data, at)
            yield channel_id, log_time


def _walk(data: memoryview, order: tuple[str, ...], wanted: dict[int, int]) -> Block:
    """The wanted messages of a chunk's records, record by record (a chunk without message indexes)."""
    times: list[int] = []
    starts: list[int] = []
    lengths: list[int] = []
    index: list[int] = []
    unpack, head = _U64.unpack_from, _MESSAGE.unpack_from
    at, end = 0, len(data)
    while at + 9 <= end:
        op, (size,) = data[at], unpack(data, at + 1)
        body, at = at + 9, at + 9 + size
        if at > end:
            raise BrokenError("a record runs past its chunk")
        if op == _OP_MESSAGE:
            channel_id, _, log_time, _ = head(data, body)
            k = wanted.get(channel_id)
            if k is not None:
                times.append(log_time)
                starts.append(body + _MESSAGE.size)
                lengths.append(size - _MESSAGE.size)
                index.append(k)
    return Block(
        np.asarray(times, dtype=np.int64),
        np.asarray(index, dtype=np.int32),
        order,
        data,
        np.asarray(starts, dtype=np.int64),
        np.asarray(lengths, dtype=np.int64),
    )


def _clusters(chunks: list[_ChunkIndex]) -> Iterator[list[_ChunkIndex]]:
    """Chunks (sorted by start) grouped where their time ranges overlap: each group is read and merged at once."""
    group: list[_ChunkIndex] = []
    end = -1
    for c in chunks:
        if group and c.start_ns > end:
            yield group
            group = []
        group.append(c)
        end = max(end, c.end_ns)
    if group:
        yield group


def _merged(parts: list[Block]) -> Block:
    """Blocks of overlapping chunks as one block in time order (their bytes copied into one buffer)."""
    offsets = np.cumsum([0] + [len(p.buffer) for p in parts[:-1]])
    buffer = memoryview(b"".join(p.buffer for p in parts))
    block = Block(
        np.concatenate([p.times_ns for p in parts]),
        np.concatenate([p.topic_index for p in parts]),
        parts[0].topics,
        buffer,
        np.concatenate([p.starts + o for p, o in zip(parts, offsets, strict=True)]),
        np.concatenate([p.lengths for p in parts]),
    )
    return in_time_order(block)
