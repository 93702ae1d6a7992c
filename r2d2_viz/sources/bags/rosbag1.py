"""A ROS 1 bag (rosbag format 2.0) read without ROS, as a :class:`~r2d2_viz.sources.bags.storage.Storage`: its
records parsed by :mod:`~r2d2_viz.sources.bags.rosbag1_records` (rosbags' reader refuses bags without an index and
pre-2010 ``roslib/Header`` definitions), messages converted to CDR with the definitions of their connection headers.
Topics get a leading slash as rosbag2 gives them (``joint_states`` → ``/joint_states``); the connections of one
topic (a ``/tf`` from three publishers) are one topic. The index (chunk infos: times and counts per connection) says
which chunks to read; a bag without one (a killed recorder) is scanned once at opening; a bag cut anywhere gives
what can be read, with a note.

Pure: no rerun import.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Collection, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from r2d2_viz.arrays import I64
from r2d2_viz.msgs.definitions import Convert, from_ros1, own_store
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bags.mcap_records import merged_chunks
from r2d2_viz.sources.bags.rosbag1_cdr import convert_runs
from r2d2_viz.sources.bags.rosbag1_records import (
    MAGIC,
    OP_BAG_HEADER,
    BrokenError,
    Chunk,
    Connection,
    IndexRows,
    RecordFile,
    chunk_records,
    message_spans,
    op_of,
    time_ns,
    u32,
)
from r2d2_viz.sources.bags.storage import Block, TopicInfo, block_of, topic_tuple

_U32, _U64 = struct.Struct("<I"), struct.Struct("<Q")


class Rosbag1:
    """A ROS 1 bag, open for reading. ``Rosbag1(path)`` raises ``ValueError`` for a file that is not a ROS 1 bag
    (format 2.0) and ``OSError`` when it cannot be read."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        self._bio = self.path.open("rb")
        try:
            self._open()
        except BaseException:
            self._bio.close()
            raise

    def _open(self) -> None:
        size = os.fstat(self._bio.fileno()).st_size
        self._records = RecordFile(self._bio, size)
        magic = self._bio.read(len(MAGIC))
        if magic != MAGIC:
            if magic.startswith(b"#ROSBAG V"):
                version = magic[9:].split(b"\n")[0].decode("ascii", "replace")
                raise ValueError(
                    f"{self.path.name}: ROS 1 bag format {version}: only 2.0 is read (`rosbag fix` converts)"
                )
            raise ValueError(f"{self.path.name}: not a ROS 1 bag (no '#ROSBAG V2.0' at its start)")
        try:
            header, _, _, first = self._records.read(len(MAGIC), data=False)
            if op_of(header) != OP_BAG_HEADER:
                raise BrokenError
            (index_pos,) = _U64.unpack(header.get(b"index_pos", b"\0" * 8)[:8].ljust(8, b"\0"))
            conn_count, chunk_count = u32(header, b"conn_count"), u32(header, b"chunk_count")
        except (BrokenError, struct.error):
            raise ValueError(f"{self.path.name}: ROS 1 bag without a readable bag header") from None
        notes = []
        indexed = 0 < index_pos < size and self._records.read_index(index_pos, conn_count, chunk_count)
        if not indexed:
            cut_at = self._records.scan(first)
            notes.append(
                "no index (its recorder was killed, or the file is cut short): read by a scan"
                + (f"; it breaks off at byte {cut_at} of {size}, what follows is lost" if cut_at is not None else "")
            )
        self._converters: dict[int, Convert] = {}
        self._conn_types: dict[int, tuple[str, str]] = {}
        self._headed: set[int] = set()  # connections whose messages start with a header (bytes 0-3: its seq)
        self.bad_messages: dict[str, tuple[int, str]] = {}
        """Per topic: messages left out because they do not fit their definition (how many, the first error)."""
        self.topics: dict[str, TopicInfo] = {}
        self._topic_conns: dict[str, list[int]] = {}
        notes += self._make_topics()
        self.note = f"{self.path.name}: " + "; ".join(notes) if notes else ""

    # --- index ------------------------------------------------------------------------------------------------

    def _make_topics(self) -> list[str]:
        """Topics from the connections (those of one topic merged); notes on what cannot be read."""
        notes = []
        counts: dict[int, int] = {}
        for chunk in self._records.chunks:
            for c, n in chunk.counts.items():
                counts[c] = counts.get(c, 0) + n
        by_topic: dict[str, list[Connection]] = {}
        for conn in sorted(self._records.conns.values(), key=lambda c: c.id):
            by_topic.setdefault(conn.topic, []).append(conn)
        for topic, conns in by_topic.items():
            first = conns[0]
            same = [k for k in conns if (k.msgtype, k.definition) == (first.msgtype, first.definition)]
            if len(same) < len(conns):
                notes.append(f"{topic}: connections with other types or definitions than {first.msgtype} left out")
            try:
                convert = from_ros1(first.msgtype, first.definition)
            except MsgError as exc:
                notes.append(f"{topic}: {exc}")
                continue
            ids = [k.id for k in same]
            self._headed.update(ids if _starts_with_header(first.msgtype, first.definition) else ())
            self._conn_types.update(dict.fromkeys(ids, (first.msgtype, first.definition)))
            self._converters.update(dict.fromkeys(ids, convert))
            self._topic_conns[topic] = ids
            self.topics[topic] = TopicInfo(
                topic, first.msgtype, sum(counts.get(k, 0) for k in ids), first.definition, "ros1msg", len(ids)
            )
        return notes

    # --- messages ---------------------------------------------------------------------------------------------

    def _wanted(self, topics: Collection[str]) -> dict[int, str]:
        return {c: t for t in topics if t in self._topic_conns for c in self._topic_conns[t]}

    def _messages(
        self, chunk: Chunk, conns: dict[int, str], start: int, stop: int
    ) -> tuple[list[tuple[int, str, bytes | memoryview]], I64, I64]:
        """``(time, topic, CDR bytes)`` of the messages in ``chunk`` on ``conns`` received in ``[start, stop)``, their
        ``header.seq`` (-1: none) and ROS 1 sizes; one not fitting its definition is counted in :attr:`bad_messages`."""
        buf = self._records.chunk_data(chunk.pos, partial=True)
        index = self._records.chunk_index(chunk)
        if index is not None:
            return self._indexed_messages(buf, index, conns, start, stop)
        view = memoryview(buf)
        out: list[tuple[int, str, bytes | memoryview]] = []
        kept: list[tuple[int, int]] = []  # header.seq, ROS 1 size
        for header, s, e in chunk_records(buf):
            if header.get(b"op") != b"\x02":
                continue
            c = _U32.unpack(conn)[0] if len(conn := header.get(b"conn", b"")) == 4 else -1
            if c not in conns:
                continue
            t = time_ns(header.get(b"time", b""))
            if start <= t < stop and self._convert(out, t, c, conns[c], view[s:e]):
                kept.append((_U32.unpack_from(buf, s)[0] if c in self._headed and e - s >= 4 else -1, e - s))
        seqs, sizes = np.array(kept, dtype=np.int64).reshape(-1, 2).T
        return out, seqs, sizes

    def _indexed_messages(
        self, buf: bytes, index: dict[int, IndexRows], conns: dict[int, str], start: int, stop: int
    ) -> tuple[list[tuple[int, str, bytes | memoryview]], I64, I64]:
        """As :meth:`_messages`, the records found through the chunk's index records (no header parsed)."""
        wanted = [c for c in index if c in conns]
        if not wanted:
            return [], np.zeros(0, np.int64), np.zeros(0, np.int64)
        rows = np.concatenate([index[c] for c in wanted])
        conn_ids = np.repeat(np.array(wanted, dtype=np.int64), [len(index[c]) for c in wanted])
        keep = (rows[:, 0] >= start) & (rows[:, 0] < stop)
        rows, conn_ids = rows[keep], conn_ids[keep]
        starts, ends, ok = message_spans(np.frombuffer(buf, dtype=np.uint8), rows[:, 1])
        for c in conn_ids[~ok].tolist():
            self._bad(conns[c], "its index points outside its chunk")
        rows, conn_ids, starts, ends = rows[ok], conn_ids[ok], starts[ok], ends[ok]
        done = convert_runs(np.frombuffer(buf, dtype=np.uint8), conn_ids, starts, ends, self._conn_types)
        view = memoryview(buf)
        out: list[tuple[int, str, bytes | memoryview]] = []
        columns = (rows[:, 0].tolist(), conn_ids.tolist(), starts.tolist(), ends.tolist())
        left_out = []
        for i, (t, c, s, e) in enumerate(zip(*columns, strict=True)):
            if not self._convert(out, t, c, conns[c], view[s:e], done.get(i)):
                left_out.append(i)
        seq = _header_seq(np.frombuffer(buf, dtype=np.uint8), np.isin(conn_ids, list(self._headed)), starts, ends)
        return out, np.delete(seq, left_out), np.delete(ends - starts, left_out)

    def _convert(self, out: list[Any], t: int, conn: int, topic: str, raw: memoryview, cdr: Any = None) -> bool:
        """Appends ``(t, topic, CDR bytes)`` (``cdr`` when converted already); a message that does not fit its
        definition is counted instead (False)."""
        try:
            out.append((t, topic, self._converters[conn](raw) if cdr is None else cdr))
        except MsgError as exc:
            return self._bad(topic, str(exc))
        return True

    def _bad(self, topic: str, why: str) -> bool:
        n, first = self.bad_messages.get(topic, (0, why))
        self.bad_messages[topic] = (n + 1, first)
        return False

    @property
    def span(self) -> tuple[int, int] | None:
        """``(first, last)`` receive time in ns, from the index."""
        return _span(self._records.chunks)

    def blocks(
        self, topics: Collection[str], *, start_ns: int | None = None, stop_ns: int | None = None
    ) -> Iterator[Block]:
        """Messages on ``topics`` in ``[start_ns, stop_ns)``: one block per chunk, in time order (chunks whose times
        overlap merged as the merge reaches them: :func:`~.mcap_records.merged_chunks`); chunks the index says hold
        none of them are not read."""
        conns = self._wanted(topics)
        start = -(1 << 63) if start_ns is None else start_ns
        stop = 1 << 63 if stop_ns is None else stop_ns
        chunks = sorted(
            (
                c
                for c in self._records.chunks
                if any(k in conns for k in c.counts) and c.end_ns >= start and c.start_ns < stop
            ),
            key=lambda c: c.start_ns,
        )
        names = topic_tuple(topics)
        read = lambda chunk: _block_of(self._messages(chunk, conns, start, stop), names)  # noqa: E731
        group: list[Chunk] = []
        group_end = 0
        for chunk in [*chunks, None]:
            if group and (chunk is None or chunk.start_ns >= group_end):
                yield from merged_chunks(group, read, lambda c: (c.start_ns, c.pos))
                group = []
            if chunk is not None:
                group_end = max(group_end, chunk.end_ns + 1) if group else chunk.end_ns + 1
                group.append(chunk)

    def last(self, topic: str, *, before_ns: int | None = None) -> tuple[int, bytes] | None:
        """The last message on ``topic`` received before ``before_ns``, through the chunk infos."""
        conns = self._wanted([topic])
        before = 1 << 63 if before_ns is None else before_ns
        best: tuple[int, bytes] | None = None
        for chunk in _latest_first(self._records.chunks, conns, before):
            if best is not None and best[0] >= chunk.end_ns:
                break
            for t, _, data in self._messages(chunk, conns, -(1 << 63), before)[0]:
                if best is None or t >= best[0]:
                    best = (t, bytes(data))
        return best

    def close(self) -> None:
        self._bio.close()


def _starts_with_header(msgtype: str, definition: str) -> bool:
    """Whether ``msgtype``'s ROS 1 ``definition`` starts with a ``std_msgs/Header`` (False when it cannot be read)."""
    try:
        fields = own_store(msgtype, definition, "ros1msg").fielddefs[msgtype][1]
    except (MsgError, KeyError):
        return False
    return bool(fields) and fields[0][1] == (2, "std_msgs/msg/Header")


def _header_seq(buf: np.ndarray, headed: np.ndarray, starts: I64, ends: I64) -> I64:
    """The ``header.seq`` of the messages ``buf[starts[i]:ends[i]]`` (their first 4 bytes) where ``headed`` (-1
    elsewhere)."""
    headed = headed & (ends - starts >= 4)
    if not headed.any():
        return np.full(len(starts), -1, np.int64)
    at = np.where(headed, starts, 0)[:, None] + np.arange(4)
    seq = np.ascontiguousarray(buf[at]).view("<u4")[:, 0].astype(np.int64)
    out: I64 = np.where(headed, seq, -1)
    return out


def _latest_first(chunks: list[Chunk], conns: dict[int, str], before: int) -> list[Chunk]:
    """The chunks holding messages on ``conns`` that start before ``before``, the latest ending first."""
    return sorted(
        (c for c in chunks if any(k in conns for k in c.counts) and c.start_ns < before),
        key=lambda c: c.end_ns,
        reverse=True,
    )


def _span(chunks: list[Chunk]) -> tuple[int, int] | None:
    with_messages = [c for c in chunks if c.counts]
    if not with_messages:
        return None
    return min(c.start_ns for c in with_messages), max(c.end_ns for c in with_messages)


def _block_of(
    found: tuple[list[tuple[int, str, bytes | memoryview]], I64, I64], names: tuple[str, ...]
) -> Block | None:
    """A chunk's messages, their ``header.seq`` and their ROS 1 sizes as a block (None: none)."""
    messages, seqs, sizes = found
    return block_of(messages, names, seqs, sizes) if messages else None
