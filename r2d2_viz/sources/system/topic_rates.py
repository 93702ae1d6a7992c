"""Each topic's rate and bandwidth over a bag, as ``ros2 topic hz`` and ``ros2 topic bw`` would give over the
whole recording: messages − 1 over the span from its first to its last message, and its bytes over the same span.
One pass over the bag's storage blocks, numpy per block (``bincount`` of the sizes, ``minimum.at`` / ``maximum.at``
of the receive times); nothing is decoded. A ROS 1 topic of one publisher also gets its drops: the ``header.seq``
numbers missing. Pure; no rerun import."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.bags.storage import Block
from r2d2_viz.sources.system.topic_health import seq_gaps


@dataclass(frozen=True)
class TopicRate:
    """A topic's messages read, their bytes as the bag stores them (a ROS 1 bag's own, not their CDR), first and last
    receive times (ns) and drops."""

    count: int
    nbytes: int
    first_ns: int
    last_ns: int
    drops: int | None = None
    """``header.seq`` numbers missing between its messages; None: not known (no ROS 1 ``seq``, several publishers,
    numbers that do not grow: :func:`~.topic_health.seq_gaps`)."""

    @property
    def span_s(self) -> float:
        return (self.last_ns - self.first_ns) / 1e9

    @property
    def rate_hz(self) -> float | None:
        """Messages − 1 over the span; None under two messages or all at one time."""
        return (self.count - 1) / self.span_s if self.count > 1 and self.span_s > 0 else None

    @property
    def bandwidth(self) -> float | None:
        """Bytes per second over the span (B/s); None where there is no rate."""
        return self.nbytes / self.span_s if self.rate_hz is not None else None


def topic_rates(bag: Bag) -> dict[str, TopicRate]:
    """Every topic of ``bag`` that has messages → its :class:`TopicRate` (one pass over all of them)."""
    names = sorted(bag.topics)
    where = {t: i for i, t in enumerate(names)}
    count = np.zeros(len(names), np.int64)
    nbytes = np.zeros(len(names), np.int64)
    first = np.full(len(names), np.iinfo(np.int64).max)
    last = np.full(len(names), np.iinfo(np.int64).min)
    seqs = _Seqs({t for t in names if bag.topics[t].publishers == 1})
    for block in bag.blocks(names):
        seqs.add(block)
        index = np.array([where[t] for t in block.topics], np.int64)[block.topic_index]
        count += np.bincount(index, minlength=len(names))
        nbytes += np.bincount(index, weights=block.stored_lengths, minlength=len(names)).astype(np.int64)
        np.minimum.at(first, index, block.times_ns)
        np.maximum.at(last, index, block.times_ns)
    return {
        t: TopicRate(int(count[i]), int(nbytes[i]), int(first[i]), int(last[i]), seqs.drops(t))
        for t, i in where.items()
        if count[i]
    }


class _Seqs:
    """The drops of the ``topics`` (of one publisher each) whose every message carries a ROS 1 ``seq``."""

    def __init__(self, topics: set[str]) -> None:
        self.topics, self.last, self.missing = topics, dict[str, int](), dict[str, int]()
        self.unknown: set[str] = set()

    def add(self, block: Block) -> None:
        """The messages of ``block`` (blocks come in time order)."""
        for k, t in enumerate(block.topics):
            if t not in self.topics or t in self.unknown:
                continue
            seq = None if block.seq is None else block.seq[block.topic_index == k]
            if seq is None or (seq < 0).any():
                self.unknown.add(t)
                continue
            if len(seq):
                before = [self.last[t]] if t in self.last else []
                gaps = seq_gaps(np.r_[before, seq].astype(np.int64))
                if gaps is None:
                    self.unknown.add(t)
                    continue
                self.missing[t] = self.missing.get(t, 0) + int(gaps.sum())
                self.last[t] = int(seq[-1])

    def drops(self, topic: str) -> int | None:
        return None if topic in self.unknown or topic not in self.last else self.missing[topic]


def si(value: float, unit: str) -> str:
    """``12.3 kB/s``: three significant digits and a decimal prefix (as ``ros2 topic bw`` prints)."""
    for prefix, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if abs(value) >= scale:
            return f"{value / scale:.3g} {prefix}{unit}"
    return f"{value:.3g} {unit}"


def rate_words(rate: TopicRate | None) -> str:
    """``, 10 Hz, 3.2 kB/s`` after a topic's message count ("" where there is no rate), then ``, 3 dropped`` where
    the drops are known."""
    if rate is None:
        return ""
    drops = "" if rate.drops is None else f", {rate.drops} dropped"
    if rate.rate_hz is None or rate.bandwidth is None:
        return drops
    return f", {si(rate.rate_hz, 'Hz')}, {si(rate.bandwidth, 'B/s')}{drops}"
