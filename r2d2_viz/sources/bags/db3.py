"""A rosbag2 ``.db3`` file (SQLite storage) read with Python's own ``sqlite3``, never writing beside it.

The file is opened as an immutable, read-only URI (``file:…?mode=ro&immutable=1``, the path percent-quoted): SQLite
then takes no locks and creates no ``-journal``, ``-wal`` or ``-shm`` file, so a bag in a read-only folder opens,
also one recorded in WAL mode (rosbag2's ``resilient`` storage preset), and the folder's file list never changes.
rosbags' own reader opens the same way but puts the path into the URI unquoted, so a bag under a folder named
``run#2`` or ``100%`` could not be opened at all.

Immutable means SQLite also ignores a ``-wal`` file left beside the database by a recorder that did not finish:
what that log holds is not read, and :attr:`Db3.note` says so (folding it in would mean writing the user's file).

Tables read (every rosbag2 schema, Foxy to Rolling): ``topics(id, name, type, …)``,
``messages(topic_id, timestamp, data)`` (read in timestamp order, rosbag2's ``timestamp_idx``) and, where the bag
has it (Iron on), ``message_definitions``. Pure: no rerun import.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Collection, Iterator
from pathlib import Path
from urllib.parse import quote

import numpy as np

from r2d2_viz.sources.bags.storage import Block, TopicInfo, in_time_order, other_types_note, topic_tuple

BLOCK_ROWS = 4096
BLOCK_BYTES = 8 << 20
"""A block holds at most this many messages, or about this many bytes (a few images). Unlike an mmapped MCAP
file's, a ``.db3`` block's bytes are the program's own (anonymous) memory: each row is appended to the block's
buffer as it comes, and dropped, so a block costs its bytes once, not its rows and their joined copy."""


def readonly_uri(path: Path) -> str:
    """An SQLite URI that opens ``path`` read-only and immutable (no locks, no files created beside it)."""
    return f"file:{quote(str(path.absolute()))}?mode=ro&immutable=1"


class Db3:
    """One ``.db3`` storage file (:class:`~r2d2_viz.sources.bags.storage.Storage`); errors are sqlite3's (the
    caller makes them one line)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.problems: dict[str, int] = {}
        self.note = ""
        """A warning to give once, if the file has an unfinished write-ahead log beside it."""
        wal = path.with_name(path.name + "-wal")
        if wal.is_file() and (size := wal.stat().st_size) > 0:
            self.note = (
                f"{wal}: the recording did not finish; what its write-ahead log holds ({size:,} bytes) is not read "
                "(nothing is written beside a bag; open a copy with sqlite3 to fold it in)"
            )
        self._db = sqlite3.connect(readonly_uri(path), uri=True, check_same_thread=False)
        try:
            tables = {row[0] for row in self._db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            if not {"topics", "messages"} <= tables:
                raise sqlite3.DatabaseError("not a rosbag2 database (no topics and messages tables)")
            rows = self._db.execute(
                "SELECT topics.id, topics.name, topics.type, count(messages.topic_id) FROM topics "
                "LEFT JOIN messages ON messages.topic_id = topics.id GROUP BY topics.id ORDER BY topics.id"
            ).fetchall()
        except BaseException:
            self._db.close()
            raise
        definitions = self._definitions(tables)
        self._ids: dict[str, list[int]] = {}
        self._topic_of: dict[int, str] = {}
        self.topics: dict[str, TopicInfo] = {}
        other_types: dict[tuple[str, str, str], int] = {}
        for topic_id, name, msgtype, count in rows:
            name, msgtype = str(name), str(msgtype)
            old = self.topics.get(name)
            if old is not None and old.msgtype != msgtype:  # kept: the first one's type, as a ROS 1 bag's reader
                key = name, old.msgtype, msgtype
                other_types[key] = other_types.get(key, 0) + int(count)
                continue
            self._ids.setdefault(name, []).append(int(topic_id))
            self._topic_of[int(topic_id)] = name
            definition, encoding = definitions.get(msgtype, ("", ""))
            self.topics[name] = TopicInfo(name, msgtype, (old.count if old else 0) + int(count), definition, encoding)
        if other_types:
            self.note = "; ".join(filter(None, [self.note, other_types_note(other_types)]))
        first, last = self._db.execute("SELECT min(timestamp), max(timestamp) FROM messages").fetchone()
        self._span = (int(first), int(last)) if first is not None else None

    def _definitions(self, tables: set[str]) -> dict[str, tuple[str, str]]:
        """type → (definition, encoding) from the ``message_definitions`` table, where the bag has one."""
        if "message_definitions" not in tables:
            return {}
        rows = self._db.execute(
            "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions"
        ).fetchall()
        return {str(t): (str(d or ""), str(e or "")) for t, e, d in rows if d}

    @property
    def span(self) -> tuple[int, int] | None:
        return self._span

    def _where(self, topics: Collection[str], start_ns: int | None, stop_ns: int | None) -> tuple[str, list[int]]:
        ids = [i for t in topics for i in self._ids.get(t, [])]
        where, args = f"topic_id IN ({', '.join('?' * len(ids))})", list(ids)
        if start_ns is not None:
            where, args = f"{where} AND timestamp >= ?", [*args, start_ns]
        if stop_ns is not None:
            where, args = f"{where} AND timestamp < ?", [*args, stop_ns]
        return where, args

    def blocks(
        self, topics: Collection[str], *, start_ns: int | None = None, stop_ns: int | None = None
    ) -> Iterator[Block]:
        order = topic_tuple(topics)
        where, args = self._where(order, start_ns, stop_ns)
        if not any(self._ids.get(t) for t in order):
            return
        cursor = self._db.execute(
            f"SELECT timestamp, topic_id, data FROM messages WHERE {where} ORDER BY timestamp, id", args
        )
        rows = _Rows(order)
        for t, topic_id, data in cursor:  # row by row: a block ends at its bound, even with images of megabytes
            rows.add(int(t), self._topic_of[int(topic_id)], data)
            if len(rows) >= BLOCK_ROWS or rows.size >= BLOCK_BYTES:
                yield rows.block()
                rows = _Rows(order)
        if len(rows):
            yield rows.block()

    def last(self, topic: str, *, before_ns: int | None = None) -> tuple[int, bytes] | None:
        if not self._ids.get(topic):
            return None
        where, args = self._where([topic], None, before_ns)
        row = self._db.execute(
            f"SELECT timestamp, data FROM messages WHERE {where} ORDER BY timestamp DESC, id DESC LIMIT 1", args
        ).fetchone()
        return (int(row[0]), bytes(row[1])) if row is not None else None

    def close(self) -> None:
        self._db.close()


class _Rows:
    """A block being gathered from rows: their bytes appended to one buffer as they come (no list of rows)."""

    def __init__(self, order: tuple[str, ...]) -> None:
        self.order, self.place = order, {t: k for k, t in enumerate(order)}
        self.buffer = bytearray()
        self.times: list[int] = []
        self.index: list[int] = []
        self.lengths: list[int] = []

    def __len__(self) -> int:
        return len(self.times)

    @property
    def size(self) -> int:
        return len(self.buffer)

    def add(self, t: int, topic: str, data: bytes) -> None:
        self.times.append(t)
        self.index.append(self.place[topic])
        self.lengths.append(len(data))
        self.buffer += data

    def block(self) -> Block:
        lengths = np.asarray(self.lengths, dtype=np.int64)
        starts = np.zeros(len(lengths), dtype=np.int64)
        np.cumsum(lengths[:-1], out=starts[1:])
        times, index = np.asarray(self.times, dtype=np.int64), np.asarray(self.index, dtype=np.int32)
        return in_time_order(Block(times, index, self.order, memoryview(self.buffer), starts, lengths))
