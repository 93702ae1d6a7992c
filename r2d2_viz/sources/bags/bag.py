"""Open a ROS 2 bag without ROS: a rosbag2 directory (``metadata.yaml`` with ``.db3`` or ``.mcap`` storage, metadata
versions 1..9, i.e. up to what Rolling writes), a directory of ``.db3`` or ``.mcap`` files whose metadata.yaml
is missing (what ``ros2 bag reindex`` repairs), a single ``.mcap`` or a single ``.db3``; hand out the raw CDR messages
of a topic, in time order, with their receive times.

Nothing is ever written beside the bag: ``.db3`` files are opened read-only and immutable (:mod:`.db3`), so a bag in
a read-only folder opens, and SQLite leaves no ``-journal``, ``-wal`` or ``-shm`` file behind.

Every problem is one :class:`~r2d2_viz.errors.BagError` line naming the file; a bag that breaks off part-way
(truncated, corrupt pages) gives what could be read and one warning, "recovered N of M messages".

Message types are decoded with the ROS 2 Humble type store (``rosbags.typesys.Stores.ROS2_HUMBLE``): the types
read here (JointState, TFMessage, String) are the same on every ROS 2 distribution, and Humble ``.db3`` files
carry no message definitions. Pure: no rerun import.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from itertools import islice
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # rosbags and ruamel.yaml are imported when a bag is opened: not on a run without one
    from rosbags.rosbag2 import Reader

    from r2d2_viz.sources.bags.db3 import Db3

from r2d2_viz.errors import BagError
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.sources.bags.mcap_scan import McapScan

Warn = Callable[[str], None]


def to_stderr(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr, flush=True)


@dataclass(frozen=True)
class TopicInfo:
    name: str
    msgtype: str
    count: int
    """Messages the bag's index announces (the metadata, the MCAP summary or the database)."""


def _problem(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text[:300]


class _File:
    """One storage file. A ``.db3`` is read by :class:`Db3` (read-only, immutable: nothing written beside it). An
    MCAP file is opened by ``rosbags``, which says what it holds, and its messages are then read by
    :class:`McapScan` (several times faster than rosbags' reader), which also reads one that breaks off."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.note = ""
        """Why the file was read without its index (it breaks off), if it was."""
        self.reader: Reader | None = None
        self.db3: Db3 | None = None
        if path.suffix == ".db3":
            from r2d2_viz.sources.bags.db3 import Db3

            self.db3 = Db3(path)
            self.topics = self.db3.topics
            self.scan = None
            return
        self.scan = McapScan(path)
        from rosbags.rosbag2 import Reader

        try:
            reader = Reader(path)
            reader.open()
            self.reader = reader
            self.topics = {c.topic: (c.msgtype, c.msgcount) for c in reader.connections}
        except Exception as exc:
            if not _TRUNCATED.search(str(exc)):
                raise
            self.topics = self.scan.topics()
            count = sum(n for _, n in self.topics.values())
            if not count:
                raise
            self.note = f"{path}: the file breaks off ({_problem(exc)}): recovered {count} messages"

    def messages(self, topic: str) -> Iterator[tuple[int, bytes | memoryview]]:
        if self.db3 is not None:
            return self.db3.messages(topic)
        assert self.scan is not None  # an MCAP file: rosbags only said what it holds
        return self.scan.messages(topic)

    def close(self) -> None:
        if self.db3 is not None:
            self.db3.close()
        if self.reader is not None:
            self.reader.close()


_TRUNCATED = re.compile(r"end magic|footer|summary", re.IGNORECASE)


class Bag:
    """An open bag (use :func:`open_bag`, as a context manager)."""

    def __init__(self, path: Path, *, warn: Warn = to_stderr) -> None:
        self.path, self.warn = path, warn
        self._files: list[_File] = []
        try:
            self._open()
        except BagError:
            self.close()
            raise
        except Exception as exc:  # rosbags, sqlite3, lz4, zstd, struct ...: hostile input, one line
            self.close()
            raise BagError(f"{path}: cannot read this bag: {_problem(exc)}") from None

    def _open(self) -> None:
        path = self.path
        expected: dict[str, int] = {}
        if not path.exists():
            raise BagError(f"{path}: no such file or directory")
        if path.is_dir():
            files, expected = _directory(path)
        elif path.suffix in (".mcap", ".db3"):
            files = [path]
        else:
            raise BagError(f"{path}: not a ROS 2 bag (expected a rosbag2 directory, a .mcap or a .db3 file)")
        for file in files:
            self._files.append(_File(file))
            if self._files[-1].note and not expected:
                self.warn(self._files[-1].note)
            if (db3 := self._files[-1].db3) is not None and db3.note:
                self.warn(db3.note)
        topics: dict[str, TopicInfo] = {}
        for f in self._files:
            for topic, (msgtype, count) in f.topics.items():
                old = topics.get(topic)
                if old is not None and old.msgtype != msgtype:
                    raise BagError(f"{path}: topic {topic} has two types, {old.msgtype} and {msgtype}")
                topics[topic] = TopicInfo(topic, msgtype, (old.count if old else 0) + count)
        for topic, count in expected.items():  # the metadata's counts, where it has them
            if topic in topics:
                topics[topic] = TopicInfo(topic, topics[topic].msgtype, max(count, topics[topic].count))
        self.topics = topics
        if sum(t.count for t in topics.values()) == 0:
            raise BagError(f"{path}: empty bag (no messages)")

    @property
    def files(self) -> tuple[Path, ...]:
        """The storage files (``.mcap`` ones can go to :func:`r2d2_viz.viewer.bag_topics.log_other_topics`)."""
        return tuple(f.path for f in self._files)

    def topic_type(self, topic: str) -> str | None:
        info = self.topics.get(topic)
        return info.msgtype if info else None

    def require_type(self, topic: str, msgtype: str) -> bool:
        """Whether ``topic`` is in the bag; a BagError when it is, with another type."""
        found = self.topic_type(topic)
        if found is not None and found != msgtype:
            raise BagError(f"{self.path}: {topic} is {found}, expected {msgtype}")
        return found is not None

    def raw(self, topic: str) -> Iterator[tuple[int, bytes | memoryview]]:
        """``(receive time ns, CDR bytes)`` of every message on ``topic``, in time order (see :meth:`batches`)."""
        for batch in self.batches(topic, 4096):
            yield from batch

    def batches(self, topic: str, size: int) -> Iterator[list[tuple[int, bytes | memoryview]]]:
        """:meth:`raw` in lists of at most ``size`` messages (cheaper per message).

        If the bag breaks off, stops there with one warning (or a BagError when nothing could be read)."""
        expected = self.topics[topic].count if topic in self.topics else 0
        got = 0
        try:
            for f in self._files:
                messages = f.messages(topic)
                while batch := list(islice(messages, size)):
                    got += len(batch)
                    yield batch
        except Exception as exc:  # a truncated or corrupt storage file, whatever the library raises
            if got == 0:
                raise BagError(f"{self.path}: cannot read {topic}: {_problem(exc)}") from None
            self.warn(f"{self.path}: {topic}: recovered {got} of {expected} messages ({_problem(exc)})")
            return
        if got < expected:
            self.warn(f"{self.path}: {topic}: recovered {got} of {expected} messages")

    def deserialize(self, data: bytes | memoryview, msgtype: str) -> Any:
        """One message as rosbags' dataclass; a BagError when it cannot be decoded."""
        try:
            return typestore().deserialize_cdr(bytes(data), msgtype)
        except Exception as exc:
            raise BagError(f"{self.path}: a {msgtype} message cannot be decoded: {_problem(exc)}") from None

    def close(self) -> None:
        files, self._files = self._files, []
        for f in files:
            try:
                f.close()
            except Exception:  # closing a half-read corrupt file: nothing left to do
                pass

    def __enter__(self) -> Bag:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


def _directory(path: Path) -> tuple[list[Path], dict[str, int]]:
    """The storage files of a rosbag2 directory and its topics' message counts, from its metadata.yaml.

    The files are then read one by one: rosbags' directory reader also matches each file's topics to the
    metadata's by their QoS profiles, and finds none in bags whose metadata writes them differently (e.g. the
    Foxy bags in rosbag2's own tests), so it would yield no messages at all."""
    meta = path / "metadata.yaml"
    if not meta.is_file():
        return _storage_files(path), {}
    from ruamel.yaml import YAML

    try:
        info = YAML(typ="safe").load(meta.read_text())["rosbag2_bagfile_information"]
        compression = info.get("compression_mode") or ""
        if compression and compression.lower() != "none":
            raise BagError(
                f"{meta}: compressed bags ({info.get('compression_format')}, per {compression.lower()}) are not "
                "supported; decompress it first (ros2 bag convert)"
            )
        storage = info["storage_identifier"]
        if storage not in ("sqlite3", "mcap"):
            raise BagError(f"{meta}: storage {storage!r} is not supported (sqlite3 and mcap are)")
        files = [path / Path(str(name)).name for name in info["relative_file_paths"]]
        counts: dict[str, int] = {}
        for t in info.get("topics_with_message_count") or []:
            name = str(t["topic_metadata"]["name"])
            counts[name] = counts.get(name, 0) + int(t["message_count"])
    except BagError:
        raise
    except Exception as exc:  # YAML errors, missing keys, wrong types
        raise BagError(f"{meta}: not rosbag2 metadata: {_problem(exc)}") from None
    if missing := [f.name for f in files if not f.is_file()]:
        raise BagError(f"{path}: storage files named in metadata.yaml are missing: {', '.join(missing)}")
    return files, counts


def _natural(name: str) -> list[tuple[int, str]]:
    """Sort key putting ``bag_2.mcap`` before ``bag_10.mcap``."""
    return [(int(part), "") if part.isdigit() else (-1, part) for part in re.split(r"(\d+)", name)]


def _storage_files(path: Path) -> list[Path]:
    """The storage files of a directory without metadata.yaml (what ``ros2 bag reindex`` would index): its
    ``.db3`` or ``.mcap`` files, split files in the order of their numbers."""
    files = sorted(
        (f for f in path.iterdir() if f.suffix in (".db3", ".mcap") and f.is_file()), key=lambda f: _natural(f.name)
    )
    if not files:
        raise BagError(f"{path}: not a ROS 2 bag (no metadata.yaml, no .db3 or .mcap file in this directory)")
    if len({f.suffix for f in files}) > 1:
        raise BagError(
            f"{path}: no metadata.yaml, and both .db3 and .mcap files in this directory: give one file, "
            "or run ros2 bag reindex"
        )
    return files


def open_bag(path: str | Path, *, warn: Warn = to_stderr) -> Bag:
    """Open a bag for reading; a BagError naming the file when it is not a readable, non-empty ROS 2 bag."""
    return Bag(Path(path), warn=warn)
