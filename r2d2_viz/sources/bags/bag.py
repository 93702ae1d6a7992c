"""Open a ROS 2 bag without ROS: a rosbag2 directory (``metadata.yaml`` with ``.db3`` or ``.mcap`` storage, metadata
versions 1..9, i.e. up to what Rolling writes), a directory of ``.db3`` or ``.mcap`` files whose metadata.yaml
is missing (what ``ros2 bag reindex`` repairs), a single ``.mcap`` or a single ``.db3``; hand out the raw CDR messages
of several topics in one pass, in time order, with their receive times (:mod:`.storage`).

Nothing is ever written beside the bag: ``.db3`` files are opened read-only and immutable (:mod:`.db3`), so a bag in
a read-only folder opens, and SQLite leaves no ``-journal``, ``-wal`` or ``-shm`` file behind.

Every problem is one :class:`~r2d2_viz.errors.BagError` line naming the file; a bag that breaks off part-way
(truncated, corrupt pages, damaged chunks) gives what could be read and one warning. Pure: no rerun import.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Collection, Iterator
from pathlib import Path
from types import TracebackType
from typing import Any

from r2d2_viz.errors import BagError, listed, warn
from r2d2_viz.msgs.definitions import Convert
from r2d2_viz.msgs.typestore import MsgError, deserialize
from r2d2_viz.sources.bags.mcap_scan import McapScan
from r2d2_viz.sources.bags.merge import merged, overlapping_files
from r2d2_viz.sources.bags.storage import Block, Storage, TopicInfo, block_of, renamed, topic_name, topic_tuple

Warn = Callable[[str], None]
to_stderr: Warn = warn
"""The default: a whole ``warning:`` line on stderr."""


STORAGES = (".db3", ".mcap", ".bag")
"""Storage files a bag is made of (``.bag``: a ROS 1 bag)."""


def _open_storage(path: Path) -> Storage:
    if path.suffix == ".db3":
        from r2d2_viz.sources.bags.db3 import Db3

        return Db3(path)
    if path.suffix == ".bag":
        from r2d2_viz.sources.bags.rosbag1 import Rosbag1

        return Rosbag1(path)
    return McapScan(path)


def _problem(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text[:300]


class Bag:
    """An open bag (use :func:`open_bag`, as a context manager): its storage files read as one."""

    def __init__(self, path: Path, *, warn: Warn = to_stderr) -> None:
        self.path, self.warn = path, warn
        self._files: list[Storage] = []
        self._names: list[dict[str, list[str]]] = []
        """Per storage file (in time order): the bag's topic name → the file's own names for it."""
        self._damage_said = False
        self._convert: dict[str, Convert] = {}
        """Topics whose definitions are not Humble's layout → the conversion of each message to it."""
        self._bad: dict[str, int] = {}
        try:
            self._open()
        except BagError:
            self.close()
            raise
        except Exception as exc:  # sqlite3, lz4, zstd, struct, mmap ...: hostile input, one line
            self.close()
            raise BagError(f"{path}: cannot read this bag: {_problem(exc)}") from None

    def _open(self) -> None:
        path = self.path
        expected: dict[tuple[str, str], int] = {}
        if not path.exists():
            raise BagError(f"{path}: no such file or directory")
        if path.is_dir():
            files, expected = _directory(path)
        elif path.suffix in STORAGES:
            files = [path]
        else:
            raise BagError(
                f"{path}: not a bag (expected a rosbag2 directory, a .mcap or .db3 file, or a ROS 1 .bag file)"
            )
        for file in files:
            try:
                storage = _open_storage(file)
            except BagError:
                raise
            except Exception as exc:
                raise BagError(f"{file}: cannot read this bag: {_problem(exc)}") from None
            self._files.append(storage)
            if storage.note and any(t.count for t in storage.topics.values()):  # nothing read: the error says it
                announced = sum(expected.values()) if len(files) == 1 and "recovered" in storage.note else 0
                self.warn(f"{file}: {storage.note}" + (f" (the metadata lists {announced})" if announced else ""))
        self._files.sort(key=lambda f: f.span[0] if f.span is not None else 2**64)  # in time, whatever their names
        topics, self._names = _merged_topics(self._files, path, self.warn)
        for (topic, msgtype), count in expected.items():  # the metadata's counts, where it has them
            if topic in topics and topics[topic].msgtype == msgtype:
                topics[topic] = dataclasses.replace(topics[topic], count=max(count, topics[topic].count))
        if sum(t.count for t in topics.values()) == 0:
            raise BagError(f"{path}: empty bag (no messages)")
        self.topics, self._convert = own_definitions(path, topics, self.warn)

    @property
    def humble_topics(self) -> frozenset[str]:
        """Topics whose messages come out converted to Humble's layout (their own definitions differ)."""
        return frozenset(self._convert)

    @property
    def files(self) -> tuple[Path, ...]:
        """The storage files."""
        return tuple(f.path for f in self._files)

    @property
    def span(self) -> tuple[int, int] | None:
        """``(first, last)`` receive time (ns) of the bag's messages, from the storages' indexes."""
        spans = [s for f in self._files if (s := f.span) is not None]
        return (min(s[0] for s in spans), max(s[1] for s in spans)) if spans else None

    def file_topic(self, topic: str, file: int) -> TopicInfo | None:
        """``topic`` as the ``file``-th storage file has it (its own definition); None: not in that file."""
        own = self._names[file].get(topic) if 0 <= file < len(self._names) else None
        return self._files[file].topics[own[0]] if own else None

    def topic_type(self, topic: str) -> str | None:
        info = self.topics.get(topic)
        return info.msgtype if info else None

    def require_type(self, topic: str, msgtype: str) -> bool:
        """Whether ``topic`` is in the bag; a BagError when it is, with another type."""
        found = self.topic_type(topic)
        if found is not None and found != msgtype:
            raise BagError(f"{self.path}: {topic} is {found}, expected {msgtype}")
        return found is not None

    def blocks(
        self, topics: Collection[str], *, start_ns: int | None = None, stop_ns: int | None = None
    ) -> Iterator[Block]:
        """The messages on ``topics`` received in ``[start_ns, stop_ns)``, in time order, in one pass over each
        storage file (:meth:`Storage.blocks`): files read one after the other where their spans do not overlap,
        merged by receive time where they do (:mod:`.merge`). Damage is one warning: a file that breaks off gives
        what was read before it; damaged chunks are skipped and counted."""
        wanted = [t for t in topics if t in self.topics]
        if not wanted:
            return
        order = topic_tuple(wanted)
        said: list[str] = []  # damage met in this pass: said once, in one warning, at its end
        got = [0]
        reads = [
            (f.span, _file_blocks(f, k, own, order, (start_ns, stop_ns), len(self._files) == 1, said, got))
            for k, (f, names) in enumerate(zip(self._files, self._names, strict=True))
            if (own := [n for t in wanted for n in names.get(t, ())])
        ]
        for group in overlapping_files([span for span, _ in reads]):
            streams = [reads[k][1] for k in group]
            for block in streams[0] if len(streams) == 1 else merged(streams):
                yield self._converted(block) if self._convert.keys() & set(block.topics) else block
        for f in self._files:
            said += self._problems(f)
        expected = sum(self.topics[t].count for t in wanted)
        whole = start_ns is None and stop_ns is None and not any(f.note for f in self._files)
        if whole and got[0] < expected and not self._damage_said:
            said.append(f"{self.path}: {listed(sorted(wanted))}: recovered {got[0]} of {expected} messages")
        if said:
            self._damage_said = True
            self.warn("; ".join(said))

    def _converted(self, block: Block) -> Block:
        """``block`` with its messages of non-Humble layouts converted (those that cannot be: left out, counted)."""
        out: list[tuple[int, str, bytes | memoryview]] = []
        kept: list[int] = []
        for i, (t, topic, data) in enumerate(block.messages()):
            convert = self._convert.get(topic)
            try:
                out.append((t, topic, data if convert is None else convert(data)))
                kept.append(i)
            except MsgError:
                self._bad[topic] = self._bad.get(topic, 0) + 1
        seq = None if block.seq is None else block.seq[kept]
        return dataclasses.replace(block_of(out, block.topics, seq, block.stored_lengths[kept]), read_nbytes=block.cost)

    def _problems(self, f: Storage) -> list[str]:
        """The damaged chunks (each counted once, on the pass that met it) and messages that do not fit their
        definitions a storage met."""
        problems: dict[str, int] = getattr(f, "problems", {})
        out = [f"{f.path}: {kind}: {n} chunk{'s' if n > 1 else ''} skipped" for kind, n in sorted(problems.items())]
        problems.clear()
        bad: dict[str, tuple[int, str]] = getattr(f, "bad_messages", {})
        for topic, (n, why) in sorted(bad.items()):
            out.append(f"{f.path}: {topic}: {n} message{'s' if n > 1 else ''} that do not fit their definition ({why})")
        bad.clear()
        for topic, n in sorted(self._bad.items()):
            out.append(
                f"{f.path}: {topic}: {n} message{'s' if n > 1 else ''} that cannot be converted to Humble's layout"
            )
        self._bad.clear()
        return out

    def raw(self, topic: str) -> Iterator[tuple[int, memoryview]]:
        """``(receive time ns, CDR bytes)`` of every message on ``topic``, in time order."""
        for block in self.blocks([topic]):
            yield from block.pairs()

    def last(self, topic: str, *, before_ns: int | None = None) -> tuple[int, bytes] | None:
        """The last message on ``topic`` received before ``before_ns`` (the bag's last when None), through the
        storages' indexes: the latest of every file's (files that end before a message found are not asked)."""
        if topic not in self.topics:
            return None
        best: tuple[int, bytes] | None = None
        holding = [(f, own) for f, names in zip(self._files, self._names, strict=True) if (own := names.get(topic))]
        for f, own in sorted(holding, key=lambda h: h[0].span[1] if h[0].span is not None else -1, reverse=True):
            if best is not None and (f.span is None or f.span[1] < best[0]):
                break
            for name in own:
                try:
                    found = f.last(name, before_ns=before_ns)
                except Exception as exc:
                    self.warn(f"{f.path}: {topic}: cannot read its last message ({_problem(exc)})")
                    continue
                if found is not None and (convert := self._convert.get(topic)) is not None:
                    try:
                        found = found[0], bytes(convert(found[1]))
                    except MsgError:
                        continue
                if found is not None and (best is None or found[0] >= best[0]):
                    best = found
        return best

    def deserialize(self, data: bytes | memoryview, msgtype: str) -> Any:
        """One message as rosbags' dataclass; a MsgError when it cannot be decoded."""
        return deserialize(data, msgtype)

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


def _merged_topics(
    files: list[Storage], path: Path, warn: Warn
) -> tuple[dict[str, TopicInfo], list[dict[str, list[str]]]]:
    """The bag's topics from its files' (ROS 2 names given their leading slash, as ROS 1 names are), and per file
    the bag's topic name → the file's own names; a topic of another type in a later file is left out there, said
    once."""
    topics: dict[str, TopicInfo] = {}
    other_types: dict[str, str] = {}
    out: list[dict[str, list[str]]] = []
    for f in files:
        names: dict[str, list[str]] = {}
        for own, info in f.topics.items():
            topic = topic_name(own)
            old = topics.get(topic)
            if old is not None and old.msgtype != info.msgtype:
                other_types[topic] = f"{topic} ({info.msgtype} in {f.path.name}, left out)"
                continue
            names.setdefault(topic, []).append(own)
            count = (old.count if old else 0) + info.count
            publishers = max(old.publishers if old else 0, info.publishers)  # split files: the same publishers
            topics[topic] = dataclasses.replace(old or info, name=topic, count=count, publishers=publishers)
        out.append(names)
    if other_types:
        warn(f"{path}: topics with another type in another file: {listed(sorted(other_types.values()))}")
    return topics, out


def _file_blocks(
    f: Storage,
    k: int,
    own: list[str],
    order: tuple[str, ...],
    stretch: tuple[int | None, int | None],
    alone: bool,
    said: list[str],
    got: list[int],
) -> Iterator[Block]:
    """The ``k``-th file's blocks of its topics ``own``, renamed to the bag's ``order``; its damage noted in ``said``
    (raised, when ``alone`` in its bag and nothing could be read), the messages counted in ``got``."""
    before = got[0]
    try:
        for block in f.blocks(own, start_ns=stretch[0], stop_ns=stretch[1]):
            got[0] += len(block)
            yield dataclasses.replace(renamed(block, order), file=k)
    except Exception as exc:  # a truncated or corrupt storage file, whatever the library raises
        if got[0] == before and alone:
            raise BagError(f"{f.path}: cannot read {listed(order)}: {_problem(exc)}") from None
        said.append(f"{f.path}: the rest of the file cannot be read ({_problem(exc)})")


def own_definitions(
    path: Path, topics: dict[str, TopicInfo], warn: Warn
) -> tuple[dict[str, TopicInfo], dict[str, Convert]]:
    """Each topic decoded with the definition its bag carries: those whose layout is not Humble's get a converter
    (:func:`r2d2_viz.msgs.definitions.to_humble`); those whose definition cannot be used are left out, said in one
    line."""
    converters: dict[str, Convert] = {}
    if not any(t.definition for t in topics.values()):
        return topics, converters
    from r2d2_viz.msgs.definitions import to_humble

    unusable: dict[str, str] = {}
    for name, info in sorted(topics.items()):
        try:
            convert = to_humble(info.msgtype, info.definition, info.encoding)
        except MsgError as exc:
            unusable[name] = f"{name} ({exc})"
            continue
        if convert is not None:
            converters[name] = convert
    if unusable:
        warn(f"{path}: topics whose message definitions cannot be used, not shown: {listed(unusable.values())}")
    return {n: t for n, t in topics.items() if n not in unusable}, converters


def _directory(path: Path) -> tuple[list[Path], dict[tuple[str, str], int]]:
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
        counts: dict[tuple[str, str], int] = {}
        for t in info.get("topics_with_message_count") or []:
            key = topic_name(str(t["topic_metadata"]["name"])), str(t["topic_metadata"]["type"])
            counts[key] = counts.get(key, 0) + int(t["message_count"])
    except BagError:
        raise
    except Exception as exc:  # YAML errors, missing keys, wrong types
        raise BagError(f"{meta}: not rosbag2 metadata: {_problem(exc)}") from None
    if missing := [f.name for f in files if not f.is_file()]:
        raise BagError(f"{path}: storage files named in metadata.yaml are missing: {listed(missing)}")
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
