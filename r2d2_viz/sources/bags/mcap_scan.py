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
from collections.abc import Collection, Iterator
from pathlib import Path

import numpy as np

from r2d2_viz.sources.bags.mcap_records import (
    MAGIC,
    OP_CHANNEL,
    OP_CHUNK,
    OP_DATA_END,
    OP_MESSAGE,
    OP_SCHEMA,
    BrokenError,
    Channel,
    ChunkIndex,
    Schema,
    Summary,
    chunk_data,
    clusters,
    holds,
    indexed,
    merged,
    message_times,
    read_summary,
    records,
    walk,
)
from r2d2_viz.sources.bags.storage import Block, TopicInfo, in_time_order, topic_tuple


class McapScan:
    """One MCAP storage file (see the module docstring); raises ``ValueError`` when it is not MCAP at all."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.note = ""
        self.problems: dict[str, int] = {}
        """Damage met while reading (kind → chunks skipped)."""
        self._found = Summary()
        """What a file read from the start has shown so far (its schemas and channels)."""
        self.channels: dict[int, Channel] = self._found.channels
        self.schemas: dict[int, Schema] = self._found.schemas
        self.chunks: list[ChunkIndex] | None = None
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
        summary = read_summary(self._map)
        if isinstance(summary, str):
            self.note = summary
            return False
        self.channels, self.schemas, self._counts = summary.channels, summary.schemas, summary.counts
        self.chunks, self._span = summary.chunks, summary.span
        return True

    def _topics(self) -> dict[str, TopicInfo]:
        topics: dict[str, TopicInfo] = {}
        for channel in self.channels.values():
            schema = self.schemas.get(channel.schema_id, Schema("", "", ""))
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
        chosen = [c for c in self.chunks if c.end_ns >= lo and c.start_ns < hi and holds(c, wanted)]
        for cluster in clusters(chosen):
            parts = [b for c in cluster if (b := self._chunk_block(c, order, wanted, lo, hi)) is not None]
            if len(parts) == 1:
                yield parts[0]
            elif parts:
                yield merged(parts)

    def _chunk_block(
        self, c: ChunkIndex, order: tuple[str, ...], wanted: dict[int, int], lo: int, hi: int
    ) -> Block | None:
        """The wanted messages of one chunk; a damaged chunk is counted in :attr:`problems` and skipped."""
        try:
            data = chunk_data(self._map, c.offset, c.offset + c.length)
            found = indexed(self._map, c, order, wanted, data)
            block = found if found is not None else walk(data, order, wanted)
        except (BrokenError, struct.error, IndexError, ValueError, RuntimeError, OverflowError, MemoryError) as exc:
            kind = str(exc) if isinstance(exc, BrokenError) else f"cannot read ({type(exc).__name__})"
            self.problems[kind] = self.problems.get(kind, 0) + 1
            return None
        keep = (block.times_ns >= lo) & (block.times_ns < hi)
        block = block if keep.all() else block.take(np.flatnonzero(keep))
        return in_time_order(block) if len(block) else None

    # --- files without a summary ----------------------------------------------------------------------------------

    def _scan_everything(self) -> None:
        """Channels, schemas, counts and span of a file without a summary: one walk up to its first damage."""
        first, last, total = 2**64, -1, 0
        for op, _, body, start, end in self._walk_file():
            if op != OP_CHUNK:
                continue
            for channel_id, t in message_times(body, start, end):
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
            for op, at, stop in records(buf, len(MAGIC), len(buf)):
                if op == OP_DATA_END:
                    return
                if op == OP_CHUNK:
                    data = chunk_data(self._map, at - 9, stop)
                    self._note_definitions(data, 0, len(data))
                    yield op, at - 9, data, 0, len(data)
                elif op in (OP_SCHEMA, OP_CHANNEL):
                    self._note_definitions(view, at - 9, stop)
                elif op == OP_MESSAGE:
                    yield OP_CHUNK, at - 9, view, at - 9, stop
        except (BrokenError, struct.error, IndexError, ValueError, RuntimeError, OverflowError, MemoryError) as exc:
            if not self.note:
                self.note = f"the file is damaged ({exc or type(exc).__name__})"

    def _note_definitions(self, data: memoryview, start: int, end: int) -> None:
        for op, at, _ in records(data, start, end):
            if op == OP_SCHEMA:
                self._found.schema(data, at)
            elif op == OP_CHANNEL:
                self._found.channel(data, at)

    def _scan_blocks(
        self, order: tuple[str, ...], wanted: dict[int, int], start_ns: int | None, stop_ns: int | None
    ) -> Iterator[Block]:
        lo = -1 if start_ns is None else start_ns
        hi = 2**64 if stop_ns is None else stop_ns
        for _, _, data, start, end in self._walk_file():
            wanted = self._wanted(order)  # channels appear as the file goes on
            block = walk(data[start:end], order, wanted)
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
            if c.start_ns >= hi or not holds(c, wanted):
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
