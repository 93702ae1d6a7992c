"""What an MCAP file's summary may lack, found in its data section (https://mcap.dev/spec: every summary record is
optional), reading only what the missing part requires: without a Statistics record the messages are counted from
the chunks' message indexes (their lengths: no chunk is opened), a chunk without them walked record by record; a
channel (or its schema) that holds messages but has no copy in the summary is looked for from the start of the data
section until every one is found. What :mod:`.mcap_scan` completes a summary with. Pure: no rerun import.
"""

from __future__ import annotations

import mmap
from collections.abc import Iterable
from dataclasses import dataclass, field

from r2d2_viz.sources.bags.mcap_records import (
    MAGIC,
    OP_CHANNEL,
    OP_CHUNK,
    OP_DATA_END,
    OP_SCHEMA,
    READ_ERRORS,
    Channel,
    ChunkIndex,
    Schema,
    channel_at,
    chunk_data,
    index_counts,
    message_times,
    schema_at,
    walk_records,
)


@dataclass
class Definitions:
    """The channels and schemas of a file, as they are found."""

    channels: dict[int, Channel] = field(default_factory=dict)
    schemas: dict[int, Schema] = field(default_factory=dict)

    def note(self, data: mmap.mmap | memoryview, start: int, end: int) -> None:
        """The Schema and Channel records among the records in ``data[start:end]``."""
        for op, at, _ in walk_records(data, start, end):
            if op == OP_SCHEMA:
                self.schemas.update([schema_at(data, at)])
            elif op == OP_CHANNEL:
                self.channels.update([channel_at(data, at)])

    def missing(self, needed: Iterable[int]) -> bool:
        """Whether a channel of ``needed`` (or the schema it names) is still unknown."""
        known = [self.channels.get(channel_id) for channel_id in needed]
        return any(c is None or (c.schema_id and c.schema_id not in self.schemas) for c in known)


def count_messages(
    buf: mmap.mmap, chunks: list[ChunkIndex], found: Definitions
) -> tuple[dict[int, int], tuple[int, int] | None, dict[int, Exception]]:
    """Messages per channel and span of a file without Statistics, and the chunks found damaged (offset → error):
    from each chunk's message index lengths, else from its records (their definitions noted in ``found``)."""
    counts: dict[int, int] = {}
    first, last = 2**64, -1
    damaged: dict[int, Exception] = {}
    for c in chunks:
        try:
            in_chunk = index_counts(buf, c) if c.index_offsets else None
            if in_chunk is None:
                data = chunk_data(buf, c.offset, c.offset + c.length)
                found.note(data, 0, len(data))
                in_chunk = {}
                for channel_id, _ in message_times(data, 0, len(data)):
                    in_chunk[channel_id] = in_chunk.get(channel_id, 0) + 1
        except READ_ERRORS as exc:
            damaged[c.offset] = exc
            continue
        for channel_id, n in in_chunk.items():
            counts[channel_id] = counts.get(channel_id, 0) + n
        if any(in_chunk.values()):
            first, last = min(first, c.start_ns), max(last, c.end_ns)
    return counts, ((first, last) if last >= 0 else None), damaged


def find_definitions(buf: mmap.mmap, data_end: int, needed: set[int], found: Definitions) -> None:
    """The definitions of the ``needed`` channels not in ``found`` yet, from the data section: its records outside
    chunks, then each chunk's, up to the first place that completes them. Raises what a damaged file makes the
    record walk or a codec raise (:data:`~.mcap_records.READ_ERRORS`)."""
    if not found.missing(needed):
        return
    for op, at, stop in walk_records(buf, len(MAGIC), data_end):
        if op == OP_DATA_END:
            return
        if op in (OP_SCHEMA, OP_CHANNEL):
            found.note(buf, at - 9, stop)
        elif op == OP_CHUNK:
            data = chunk_data(buf, at - 9, stop)
            found.note(data, 0, len(data))
        else:
            continue
        if not found.missing(needed):
            return
