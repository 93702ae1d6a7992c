"""An MCAP file as a :class:`~r2d2_viz.sources.bags.storage.Storage`, read through its own index where it has one
(summary: channels, schemas, statistics, one chunk index per chunk; each chunk's message indexes): chunks that hold
none of the wanted topics, or lie outside the time asked for, are never read, and a chunk's wanted messages are
found from its message indexes as numpy arrays, not record by record. A file without a summary (a recorder that was
killed leaves none) is walked once when opened, record by record, up to the first damage, and the places, times
and channels of its chunks noted: later reads go through that index as through the file's own. What a valid summary
lacks (every summary record is optional) is found in the data section by :mod:`.mcap_summary`, reading only what
that needs; no chunk index: the data section is walked once as for a file without a summary. The file is mmapped:
uncompressed chunks are handed on as views of the file's pages, not copies, and one of which only some channels are
wanted is not checked against its CRC, which would read its other messages too (a message filtered out costs its
index entry, not its bytes). MCAP: https://mcap.dev/spec; lz4 and zstd come with ``rosbags``.

A damaged chunk (bad CRC, unknown compression, an index pointing past the end) is skipped and counted in
:attr:`McapScan.problems`; the bag says it once. Measured against the ``mcap`` library (the format's reference
reader) in ``benchmarks/mcap_readers.py``. Pure: no rerun import.
"""

from __future__ import annotations

import contextlib
import mmap
import struct
from collections.abc import Collection, Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np

from r2d2_viz.sources.bags.mcap_prefix import wanted_part
from r2d2_viz.sources.bags.mcap_records import (
    HEAD,
    MAGIC,
    OP_CHANNEL,
    OP_CHUNK,
    OP_CHUNK_INDEX,
    OP_DATA_END,
    OP_FOOTER,
    OP_MESSAGE,
    OP_SCHEMA,
    OP_STATISTICS,
    READ_ERRORS,
    U64,
    BrokenError,
    Channel,
    ChunkIndex,
    Schema,
    channel_at,
    chunk_data,
    chunk_index,
    holds,
    indexed,
    merged_chunks,
    message_times,
    overlapping,
    schema_at,
    statistics,
    walk_messages,
    walk_records,
)
from r2d2_viz.sources.bags.mcap_summary import Definitions, count_messages, find_definitions
from r2d2_viz.sources.bags.storage import Block, TopicInfo, in_time_order, other_types_note, topic_tuple


class McapScan:
    """One MCAP storage file (see the module docstring); raises ``ValueError`` when it is not MCAP at all."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.note = ""
        self.problems: dict[str, int] = {}  # damage met while reading (kind → chunks skipped); the bag says it
        self._damaged: set[int] = set()  # file offsets of the chunks found damaged (not read again)
        self._found = Definitions()
        self.channels: dict[int, Channel] = self._found.channels
        self.schemas: dict[int, Schema] = self._found.schemas
        self.chunks: list[ChunkIndex] | None = None
        """The chunk index: the summary's, or the one noted by the walk of a file without one (None: messages lie
        outside chunks, and every read walks the file from the start)."""
        self._counts: dict[int, int] = {}
        self._span: tuple[int, int] | None = None
        self._loose: np.ndarray | None = None
        self._other_types: set[int] = set()  # channels left out: no schema, or not their topic's first type
        with path.open("rb") as f:
            size = f.seek(0, 2)
            if size < len(MAGIC):
                raise ValueError("not an MCAP file (too short)")
            self._map = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        if self._map[: len(MAGIC)] != MAGIC:
            raise ValueError("not an MCAP file (no magic)")
        if not self._read_summary():
            self._scan_everything()
        self.topics, self._other_types, other_types = _topics(self.channels, self.schemas, self._counts)
        self.note = "; ".join(filter(None, [self.note, other_types]))

    # --- the summary --------------------------------------------------------------------------------------------

    def _read_summary(self) -> bool:
        """Channels, schemas, counts and chunk indexes from the summary; False when the file has none usable."""
        buf, size = self._map, len(self._map)
        footer = size - len(MAGIC) - 29
        if footer < len(MAGIC) or buf[size - len(MAGIC) :] != MAGIC or buf[footer] != OP_FOOTER:
            self.note = "the file breaks off (no footer, no index)"
            return False
        summary_start, offsets_start, _ = struct.unpack_from("<QQI", buf, footer + 9)
        if summary_start == 0:
            return False  # a valid file without a summary: read from the start, no warning
        end = offsets_start or footer
        if not len(MAGIC) <= summary_start <= end <= footer:
            self.note = "its summary points outside the file"
            return False
        chunks: list[ChunkIndex] = []
        counted = False
        try:
            for op, at, stop in walk_records(buf, summary_start, end):
                if op == OP_SCHEMA:
                    self.schemas.update([schema_at(buf, at)])
                elif op == OP_CHANNEL:
                    self.channels.update([channel_at(buf, at)])
                elif op == OP_CHUNK_INDEX:
                    chunks.append(chunk_index(buf, at, stop, size))
                elif op == OP_STATISTICS:
                    span, self._counts = statistics(buf, at, stop)
                    self._span, counted = span or self._span, True
        except (BrokenError, struct.error, IndexError) as exc:
            self.note = f"its summary is damaged ({exc or type(exc).__name__})"
            self.channels.clear()
            self.schemas.clear()
            self._counts = {}
            return False
        if not chunks and (not counted or self._span is not None):
            return False  # no chunk index (or messages outside chunks): one walk through the data section finds them
        self.chunks = sorted(chunks, key=lambda c: (c.start_ns, c.offset))
        if not counted:  # no Statistics record: counted from the chunks (damaged ones skipped)
            self._counts, self._span, damaged = count_messages(buf, self.chunks, self._found)
            for c in (c for c in self.chunks if c.offset in damaged):
                self._skip(c, damaged[c.offset])
        elif chunks and self._span is None:
            self._span = (min(c.start_ns for c in chunks), max(c.end_ns for c in chunks))
        try:  # channels (and their schemas) with messages but no copy in the summary
            find_definitions(buf, summary_start, {c for c, n in self._counts.items() if n}, self._found)
        except READ_ERRORS as exc:
            self.note = f"its data section is damaged ({exc or type(exc).__name__})"
        return True

    # --- reading ------------------------------------------------------------------------------------------------

    @property
    def span(self) -> tuple[int, int] | None:
        return self._span

    def _wanted(self, topics: Collection[str]) -> dict[int, int]:
        """channel id → its topic's index in :func:`topic_tuple` order."""
        order, left_out = topic_tuple(topics), self._other_types
        return {c.id: order.index(c.topic) for c in self.channels.values() if c.topic in order and c.id not in left_out}

    def blocks(
        self, topics: Collection[str], *, start_ns: int | None = None, stop_ns: int | None = None
    ) -> Iterator[Block]:
        order = topic_tuple(topics)
        wanted = self._wanted(order)
        lo = -1 if start_ns is None else start_ns
        hi = 2**64 if stop_ns is None else stop_ns
        if self.chunks is None:
            found = _loose_block(self._loose, self._map, order, wanted, lo, hi) if self._loose is not None else None
            yield from (found,) if found is not None and len(found) else self._scan_blocks(order, wanted, lo, hi)
            return
        chosen = [c for c in self.chunks if c.end_ns >= lo and c.start_ns < hi and holds(c, wanted)]
        for cluster in overlapping(chosen):
            if len(cluster) == 1:
                block = self._chunk_block(cluster[0], order, wanted, lo, hi)
                yield from (block,) if block is not None else ()
            else:
                read = lambda c: self._chunk_block(c, order, wanted, lo, hi)  # noqa: E731
                yield from merged_chunks(cluster, read, lambda c: (c.start_ns, c.offset))

    def _chunk_block(
        self, c: ChunkIndex, order: tuple[str, ...], wanted: dict[int, int], lo: int, hi: int
    ) -> Block | None:
        """The wanted messages of one chunk; a damaged chunk is counted in :attr:`problems` (once) and skipped."""
        if c.offset in self._damaged:
            return None
        try:
            part = wanted_part(self._map, c, wanted, lo, hi)  # a compressed chunk: up to its last wanted message
            data = part if part is not None else _records(self._map, c, wanted)
            found = indexed(self._map, c, order, wanted, data)
            if found is None and part is not None:  # its index does not fit that part: the whole chunk
                data = chunk_data(self._map, c.offset, c.offset + c.length)
                found = indexed(self._map, c, order, wanted, data)
            block = found if found is not None else walk_messages(data, order, wanted)
        except READ_ERRORS as exc:
            self._skip(c, exc)
            return None
        keep = (block.times_ns >= lo) & (block.times_ns < hi)
        block = block if keep.all() else block.take(np.flatnonzero(keep))
        return in_time_order(_read_for(block, data, self._map)) if len(block) else None

    def _skip(self, c: ChunkIndex, exc: BaseException) -> None:
        """A damaged chunk: counted in :attr:`problems` (once) and not read again."""
        if c.offset in self._damaged:
            return
        kind = str(exc) if isinstance(exc, BrokenError) else f"cannot read ({type(exc).__name__})"
        self.problems[kind] = self.problems.get(kind, 0) + 1
        self._damaged.add(c.offset)

    # --- files without a summary ----------------------------------------------------------------------------------

    def _scan_everything(self) -> None:
        """Channels, schemas, counts and span of a file without a summary: one walk up to its first damage, noting
        its chunks' places, times and channels (later reads go through that index unless a message is outside)."""
        self._counts, self._span, total, self.chunks, self._loose = _scan_index(self._walk_file(), self._map)
        if self.note:
            self.note = f"{self.note}: recovered {total} messages"

    def _walk_file(self) -> Iterator[tuple[int, int, memoryview, int, int]]:
        """``(op, file offset, buffer, start, end)`` of the data section's records — a chunk's decompressed
        records, or a record outside chunks — noting schemas and channels, until the file ends or breaks."""
        buf = self._map
        view = memoryview(buf)
        try:
            for op, at, stop in walk_records(buf, len(MAGIC), len(buf)):
                if op == OP_DATA_END:
                    return
                if op == OP_CHUNK:
                    data = chunk_data(self._map, at - 9, stop)
                    self._found.note(data, 0, len(data))
                    yield op, at - 9, data, 0, len(data)
                elif op in (OP_SCHEMA, OP_CHANNEL):
                    self._found.note(view, at - 9, stop)
                elif op == OP_MESSAGE:
                    yield OP_CHUNK, at - 9, view, at - 9, stop
        except READ_ERRORS as exc:
            if not self.note:
                self.note = f"the file is damaged ({exc or type(exc).__name__})"

    def _scan_blocks(self, order: tuple[str, ...], wanted: dict[int, int], lo: int, hi: int) -> Iterator[Block]:
        for _, _, data, start, end in self._walk_file():
            wanted = self._wanted(order)  # channels appear as the file goes on
            block = walk_messages(data[start:end], order, wanted)
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
        best: tuple[int, bytes] | None = None
        for c in sorted(self.chunks, key=lambda c: c.end_ns, reverse=True):
            if best is not None and c.end_ns < best[0]:
                break  # chunks may overlap in time: one that ends later may hold only earlier messages of it
            if c.start_ns >= hi or not holds(c, wanted):
                continue
            part = self._chunk_block(c, (topic,), wanted, -1, hi)
            if part is not None and (best is None or int(part.times_ns[-1]) >= best[0]):
                best = int(part.times_ns[-1]), bytes(part.data(len(part) - 1))
        return best

    def close(self) -> None:
        with contextlib.suppress(BufferError):  # blocks still hold views of its pages: it closes when they go
            self._map.close()


def _records(buf: mmap.mmap, c: ChunkIndex, wanted: dict[int, int]) -> memoryview:
    """A chunk's records (:func:`chunk_data`): an uncompressed one of which only some channels are wanted is not
    checked against its CRC, which would read its other messages' bytes too."""
    some = bool(c.index_offsets) and not c.index_offsets.keys() <= wanted.keys()
    return chunk_data(buf, c.offset, c.offset + c.length, part=some)


def _topics(
    channels: dict[int, Channel], schemas: dict[int, Schema], counts: dict[int, int]
) -> tuple[dict[str, TopicInfo], set[int], str]:
    """The topics of the channels, the channels left out and a note on them: those whose type is not their topic's
    first channel's (a topic recorded with two types keeps the first, as a ROS 1 bag's reader does)."""
    topics: dict[str, TopicInfo] = {}
    left: dict[tuple[str, str, str], int] = {}
    other_types: set[int] = set()
    for channel in sorted(channels.values(), key=lambda c: c.id):
        if not channel.schema_id:  # no schema (MCAP's schema id 0): nothing a ROS message could be decoded by
            other_types.add(channel.id)
            continue
        schema = schemas.get(channel.schema_id, Schema("", "", ""))
        old = topics.get(channel.topic)
        if old is not None and old.msgtype != schema.name:
            other_types.add(channel.id)
            key = channel.topic, old.msgtype, schema.name
            left[key] = left.get(key, 0) + counts.get(channel.id, 0)
            continue
        count = (old.count if old else 0) + counts.get(channel.id, 0)
        topics[channel.topic] = TopicInfo(channel.topic, schema.name, count, schema.data, schema.encoding)
    return topics, other_types, other_types_note(left)


def _scan_index(
    walked: Iterator[tuple[int, int, memoryview, int, int]], buf: mmap.mmap
) -> tuple[dict[int, int], tuple[int, int] | None, int, list[ChunkIndex] | None, np.ndarray | None]:
    """Counts per channel, span, message total, chunk index of a walk through a file (:meth:`McapScan._walk_file`)
    (None when messages lie outside chunks) and the index of those messages (None unless all are)."""
    counts: dict[int, int] = {}
    first, last, total = 2**64, -1, 0
    chunks: list[ChunkIndex] = []
    loose: list[tuple[int, int, int, int]] = []  # messages outside chunks: time, channel, record start, record end
    for op, offset, body, start, end in walked:
        if op != OP_CHUNK:
            continue
        times: list[int] = []
        channels: set[int] = set()
        for channel_id, t in message_times(body, start, end):
            counts[channel_id] = counts.get(channel_id, 0) + 1
            times.append(t)
            channels.add(channel_id)
        if times:
            first, last, total = min(first, *times), max(last, *times), total + len(times)
            if start == 0:  # a chunk's records (start != 0: a message outside chunks)
                (size,) = U64.unpack_from(buf, offset + 1)
                chunks.append(ChunkIndex(min(times), max(times), offset, 9 + size, {}, frozenset(channels)))
            else:
                loose.append((times[0], next(iter(channels)), start, end))
    index = sorted(chunks, key=lambda c: (c.start_ns, c.offset)) if not loose else None
    rows = np.array(loose, dtype=np.int64).reshape(-1, 4)
    found = rows[np.argsort(rows[:, 0], kind="stable")] if loose and not chunks else None  # both: every read walks
    return counts, ((first, last) if total else None), total, index, found


def _loose_block(
    loose: np.ndarray, buf: mmap.mmap, order: tuple[str, ...], wanted: dict[int, int], lo: int, hi: int
) -> Block:
    """The wanted messages of a file whose messages lie outside chunks (``loose``: rows of time, channel, record
    start, record end, in time order), as one block over the file's pages."""
    topic_of = np.full(1 << 16, -1, dtype=np.int32)
    topic_of[list(wanted)] = list(wanted.values())
    index = topic_of[loose[:, 1]]
    keep = (index >= 0) & (loose[:, 0] >= lo) & (loose[:, 0] < hi)
    rows = loose[keep]
    return Block(
        rows[:, 0].copy(), index[keep], order, memoryview(buf), rows[:, 2] + HEAD, rows[:, 3] - rows[:, 2] - HEAD
    )


def _read_for(block: Block, data: memoryview, buf: mmap.mmap) -> Block:
    """``block`` of a chunk's ``data``, counted as what its reading took: a compressed chunk was decompressed whole
    (:attr:`Block.read_nbytes`), and when only a few of its messages were wanted they are copied out, so the
    decompressed chunk does not stay alive with them (a window of a few small topics would keep most of the file's
    chunks otherwise). An uncompressed chunk's messages are views of the file's pages: nothing more was read."""
    if data.obj is buf:
        return block
    counted = replace(block, read_nbytes=len(data))
    return counted.compacted() if 4 * block.nbytes < len(data) else counted
