"""What every bag storage offers, whatever its format (``.db3``, ``.mcap``, ROS 1 ``.bag``): its topics with their
types (and message definitions, where the file carries them), its time span, and its messages as :class:`Block` s:
several topics in one pass, in time order, only the stretch asked for, reading through the file's index what it has
one. A block is a run of messages over one buffer, so that messages of one layout decode as one numpy view.

Pure: no rerun import.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from r2d2_viz.arrays import I64


@dataclass(frozen=True)
class TopicInfo:
    name: str
    msgtype: str
    """ROS 2 type name, ``pkg/msg/Type`` (a ROS 1 storage converts ``pkg/Type``)."""
    count: int
    """Messages the storage's index announces (the metadata, the MCAP summary, the database, the ROS 1 index)."""
    definition: str = ""
    """The message definition the file carries for this topic ("" where it carries none: ``.db3`` files)."""
    encoding: str = ""
    """The definition's format: ``ros2msg``, ``ros2idl`` or ``ros1msg`` ("" without one)."""
    publishers: int = 0
    """Its publishers, where the file says (a ROS 1 bag's connections); 0: not said."""


@dataclass(frozen=True, eq=False)
class Block:
    """Messages over one buffer, in time order: message ``i`` is on ``topics[topic_index[i]]``, received at
    ``times_ns[i]``, its (CDR) bytes ``buffer[starts[i] : starts[i] + lengths[i]]``."""

    times_ns: I64
    topic_index: np.ndarray  # (n,) int32
    topics: tuple[str, ...]
    buffer: memoryview
    starts: I64
    lengths: I64
    read_nbytes: int = 0
    """Bytes the storage read or decompressed to give these messages, where that is more than their own (a
    compressed chunk, decompressed whole for a few of its messages); 0: just theirs."""
    file: int = -1
    """Which of its bag's storage files the messages come from (-1: several, or not said): their definitions."""
    seq: I64 | None = None
    """Each message's ROS 1 ``header.seq`` (-1: none), which the conversion to CDR drops; None: not read (a ROS 2
    storage)."""
    sizes: I64 | None = None
    """Each message's size as the bag stores it, where ``lengths`` are of a conversion (a ROS 1 message as CDR, a
    layout converted to Humble's); None: ``lengths`` are the bag's own."""

    def __len__(self) -> int:
        return len(self.times_ns)

    @property
    def stored_lengths(self) -> I64:
        """Each message's size as the bag stores it (what ``ros2 topic bw`` / ``rostopic bw`` would count)."""
        return self.lengths if self.sizes is None else self.sizes

    @property
    def nbytes(self) -> int:
        return int(self.lengths.sum())

    @property
    def cost(self) -> int:
        """What reading it took: its bytes, or the bytes read for it where more (windows are sized by this)."""
        return max(self.nbytes, self.read_nbytes)

    def data(self, i: int) -> memoryview:
        start = int(self.starts[i])
        return self.buffer[start : start + int(self.lengths[i])]

    def rows(self, topic: str) -> np.ndarray:
        """The rows on ``topic`` (indices, in time order)."""
        if topic not in self.topics:
            return np.zeros(0, dtype=np.int64)
        return np.flatnonzero(self.topic_index == self.topics.index(topic))

    def take(self, rows: np.ndarray) -> Block:
        """The block of these rows (same buffer, no copy; what was read for the whole block stays counted)."""
        return Block(
            self.times_ns[rows],
            self.topic_index[rows],
            self.topics,
            self.buffer,
            self.starts[rows],
            self.lengths[rows],
            self.read_nbytes,
            self.file,
            None if self.seq is None else self.seq[rows],
            None if self.sizes is None else self.sizes[rows],
        )

    def compacted(self) -> Block:
        """The block over a buffer of its own messages only (copied), so that a big buffer it was read from (a
        decompressed chunk) can go; what was read stays counted."""
        starts = np.zeros(len(self), dtype=np.int64)
        np.cumsum(self.lengths[:-1], out=starts[1:])
        gather = np.repeat(self.starts - starts, self.lengths) + np.arange(self.nbytes, dtype=np.int64)
        data = np.frombuffer(self.buffer, dtype=np.uint8)[gather]
        return Block(
            self.times_ns,
            self.topic_index,
            self.topics,
            data.data,
            starts,
            self.lengths,
            self.cost,
            self.file,
            self.seq,
            self.sizes,
        )

    def messages(self) -> Iterator[tuple[int, str, memoryview]]:
        """``(time ns, topic, data)`` of each message, in order."""
        for i in range(len(self)):
            yield int(self.times_ns[i]), self.topics[int(self.topic_index[i])], self.data(i)

    def pairs(self) -> list[tuple[int, memoryview]]:
        """``(time ns, data)`` of each message (the decoders' input)."""
        return [(int(self.times_ns[i]), self.data(i)) for i in range(len(self))]


def block_of(
    messages: list[tuple[int, str, bytes | memoryview]],
    topics: tuple[str, ...],
    seq: I64 | None = None,
    sizes: I64 | None = None,
) -> Block:
    """A block from separate messages (storages without one buffer per stretch): their bytes joined once; ``seq``:
    their ROS 1 ``header.seq`` (:attr:`Block.seq`); ``sizes``: as the bag stores them (:attr:`Block.sizes`)."""
    index = {t: k for k, t in enumerate(topics)}
    lengths = np.fromiter((len(m[2]) for m in messages), dtype=np.int64, count=len(messages))
    starts = np.zeros(len(messages), dtype=np.int64)
    if len(messages):
        np.cumsum(lengths[:-1], out=starts[1:])
    times = np.fromiter((m[0] for m in messages), dtype=np.int64, count=len(messages))
    topic_index = np.fromiter((index[m[1]] for m in messages), dtype=np.int32, count=len(messages))
    data = memoryview(b"".join(m[2] for m in messages))
    return in_time_order(Block(times, topic_index, topics, data, starts, lengths, seq=seq, sizes=sizes))


def in_time_order(block: Block) -> Block:
    """The block sorted by time (stable: messages received at one time keep their file order)."""
    if len(block) < 2 or bool(np.all(block.times_ns[1:] >= block.times_ns[:-1])):
        return block
    return block.take(np.argsort(block.times_ns, kind="stable"))


class Storage(Protocol):
    """One storage file of a bag, open for reading (a ``.db3``, an ``.mcap``, a ROS 1 ``.bag``)."""

    path: Path
    topics: dict[str, TopicInfo]
    note: str
    """A warning to give once when the file was opened (it breaks off, it has no index), or ""."""

    @property
    def span(self) -> tuple[int, int] | None:
        """``(first, last)`` receive time in ns of its messages, from its index (None: no message)."""
        ...

    def blocks(
        self, topics: Collection[str], *, start_ns: int | None = None, stop_ns: int | None = None
    ) -> Iterator[Block]:
        """The messages on ``topics`` received in ``[start_ns, stop_ns)``, in time order, as blocks; what the index
        says holds none of them is not read. Raises whatever the file's damage makes the library raise (the
        :class:`~r2d2_viz.sources.bags.bag.Bag` turns it into one warning)."""
        ...

    def last(self, topic: str, *, before_ns: int | None = None) -> tuple[int, bytes] | None:
        """``(time ns, data)`` of the last message on ``topic`` received before ``before_ns`` (the whole file's
        last when None), found through the index; None when there is none."""
        ...

    def close(self) -> None: ...


def other_types_note(left: dict[tuple[str, str, str], int]) -> str:
    """The note on topics recorded with two types, from ``(topic, type kept, type left out) → messages left out``:
    each topic keeps the type it was first recorded with (as a ROS 1 bag's reader keeps its first connection's)."""
    return "; ".join(
        f"{topic}: {n} {other} message{'s' if n != 1 else ''} left out (the topic is {kept}, as first recorded)"
        for (topic, kept, other), n in sorted(left.items())
    )


def topic_name(name: str) -> str:
    """A topic's full name: one leading slash, no empty parts (``tf`` → ``/tf``, as rosbag2 records names)."""
    return "/" + "/".join(p for p in name.split("/") if p)


def renamed(block: Block, order: tuple[str, ...]) -> Block:
    """``block`` with its topics (a file's own names) given as their full names' places in ``order``."""
    if block.topics == order:
        return block
    places = np.array([order.index(topic_name(t)) for t in block.topics], dtype=np.int32)
    return Block(
        block.times_ns,
        places[block.topic_index],
        order,
        block.buffer,
        block.starts,
        block.lengths,
        file=block.file,
        seq=block.seq,
        sizes=block.sizes,
    )


def topic_tuple(topics: Collection[str]) -> tuple[str, ...]:
    """Topics in a stable order (a block's ``topics``)."""
    return tuple(sorted(set(topics)))
