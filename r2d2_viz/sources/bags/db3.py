"""A rosbag2 ``.db3`` file (SQLite storage) read with Python's own ``sqlite3``, never writing beside it.

The file is opened as an immutable, read-only URI (``file:…?mode=ro&immutable=1``, the path percent-quoted): SQLite
then takes no locks and creates no ``-journal``, ``-wal`` or ``-shm`` file, so a bag in a read-only folder opens,
also one recorded in WAL mode (rosbag2's ``resilient`` storage preset), and the folder's file list never changes.
rosbags' own reader opens the same way but puts the path into the URI unquoted, so a bag under a folder named
``run#2`` or ``100%`` could not be opened at all.

Immutable means SQLite also ignores a ``-wal`` file left beside the database by a recorder that did not finish:
what that log holds is not read, and :attr:`Db3.note` says so (folding it in would mean writing the user's file).

Tables read (every rosbag2 schema, Foxy to Rolling): ``topics(id, name, type, …)`` and
``messages(topic_id, timestamp, data)``. Pure: no rerun import.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import quote


def readonly_uri(path: Path) -> str:
    """An SQLite URI that opens ``path`` read-only and immutable (no locks, no files created beside it)."""
    return f"file:{quote(str(path.absolute()))}?mode=ro&immutable=1"


class Db3:
    """The topics and messages of one ``.db3`` file; errors are sqlite3's (the caller makes them one line)."""

    def __init__(self, path: Path) -> None:
        self.path = path
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
        self._ids: dict[str, list[int]] = {}
        self.topics: dict[str, tuple[str, int]] = {}
        """``topic: (message type, message count)``."""
        for topic_id, name, msgtype, count in rows:
            name, msgtype = str(name), str(msgtype)
            self._ids.setdefault(name, []).append(int(topic_id))
            old = self.topics.get(name)
            if old is not None and old[0] != msgtype:
                raise sqlite3.DatabaseError(f"topic {name} has two types, {old[0]} and {msgtype}")
            self.topics[name] = (msgtype, (old[1] if old else 0) + int(count))

    def messages(self, topic: str) -> Iterator[tuple[int, bytes]]:
        """``(receive time ns, CDR bytes)`` of the topic's messages, in time order."""
        ids = self._ids.get(topic, [])
        if not ids:
            return iter(())
        cursor = self._db.execute(
            f"SELECT timestamp, data FROM messages WHERE topic_id IN ({', '.join('?' * len(ids))}) ORDER BY timestamp",
            ids,
        )
        return ((int(t), bytes(data)) for t, data in cursor)

    def close(self) -> None:
        self._db.close()
