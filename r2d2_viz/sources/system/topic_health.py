"""Each topic's health over time, from a bag: its rate (Hz) and bandwidth (B/s) over a sliding window, for
messages that start with a ``std_msgs/Header`` their mean latency (receive time − header stamp) over the same
window, and, for a ROS 1 topic of one publisher, its drops (``header.seq`` numbers missing, counted at the message
after them) in the window; sampled every :data:`PERIOD_NS` from the topic's first message, and at its last. One pass
over the storage blocks (headers read from the bytes, :func:`~.tf_read.header_columns`), then cumulative sums and
``searchsorted`` per topic. Pure; no rerun import."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from r2d2_viz.arrays import F64, I64
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.system.tf_read import header_columns, header_first
from r2d2_viz.sources.system.time_base import TimeBase, header_base

PERIOD_NS = 500_000_000
WINDOW_NS = 2_000_000_000
OTHER_CLOCK_NS = 3600 * 1_000_000_000
"""Header stamps whose median latency exceeds an hour are on another clock (``use_sim_time``): no latency."""


@dataclass(frozen=True)
class TopicHealth:
    """One topic's samples: at ``times_ns``, the rate and bandwidth over the window before, the mean latency
    (s; NaN where no message of the window had a header, or its type has none), and the drops (NaN: not known)."""

    topic: str
    times_ns: I64
    rate_hz: F64
    bandwidth: F64
    latency_s: F64
    drops: F64 | None = None
    """Sequence numbers missing in the window (:func:`seq_gaps`); None: not known (no ROS 1 ``seq``, several
    publishers, each counting its own, or numbers that do not grow)."""

    def retimed(self, base: TimeBase) -> TopicHealth:
        """The same samples at ``base``'s times (the run's timeline: :mod:`~.time_base`)."""
        return dataclasses.replace(self, times_ns=base(self.times_ns))


def read_messages(
    bag: Bag, start_ns: int | None = None, stop_ns: int | None = None
) -> dict[str, tuple[I64, I64, I64, I64]]:
    """topic → (receive times, sizes, header stamps or -1, ROS 1 ``header.seq`` or -1) of every message, in time
    order."""
    headed = {t for t, info in bag.topics.items() if header_first(info)}
    parts: dict[str, list[tuple[I64, I64, I64, I64]]] = {}
    for block in bag.blocks(sorted(bag.topics), start_ns=start_ns, stop_ns=stop_ns):
        for k, topic in enumerate(block.topics):
            rows = np.flatnonzero(block.topic_index == k)
            if not len(rows):
                continue
            stamps = np.full(len(rows), -1, np.int64)
            if topic in headed:
                _, got, ok = header_columns(block, rows)
                stamps[ok] = got[ok]
            seq = np.full(len(rows), -1, np.int64) if block.seq is None else block.seq[rows]
            parts.setdefault(topic, []).append((block.times_ns[rows], block.stored_lengths[rows], stamps, seq))
    return {t: tuple(np.concatenate(c) for c in zip(*p, strict=True)) for t, p in parts.items()}  # type: ignore[misc]


def seq_gaps(seq: I64) -> I64 | None:
    """Per message (in receive order), the sequence numbers missing since the one before: ``seq[i] - seq[i-1] - 1``
    (0 for the first); None when the numbers ever fail to grow: several publishers share the topic (a ROS 1 bag
    records them on one connection, as ``/rosout``), one restarted, or none sets its ``seq``."""
    steps = np.diff(seq)
    if (steps < 1).any():
        return None
    gaps: I64 = np.r_[0, steps - 1].astype(np.int64)
    return gaps


def health(
    topic: str,
    times: I64,
    sizes: I64,
    stamps: I64,
    seq: I64 | None = None,
    *,
    period_ns: int = PERIOD_NS,
    window_ns: int = WINDOW_NS,
) -> TopicHealth:
    """``topic``'s series from its messages' receive times, sizes, header stamps (-1: none) and, where known, the
    ``header.seq`` of its one publisher (None or any -1: no drops)."""
    order = np.argsort(times, kind="stable")
    times, sizes, stamps = times[order], sizes[order], stamps[order]
    grid = np.arange(int(times[0]), int(times[-1]) + 1, period_ns, dtype=np.int64)
    grid = grid if grid[-1] == times[-1] else np.r_[grid, times[-1]]  # the last message counted too
    hi = np.searchsorted(times, grid, side="right")
    lo = np.searchsorted(times, grid - window_ns, side="right")
    span = np.minimum(window_ns, np.maximum(grid - int(times[0]), 1)) / 1e9  # the window, or what of it has passed
    partial = grid - window_ns < times[0]  # the window reaches back before the first message: it starts the span
    count = (hi - lo - partial).astype(np.float64)
    nbytes = np.r_[0, np.cumsum(sizes)]
    sent = nbytes[hi] - nbytes[lo] - np.where(partial, sizes[0], 0)
    headed = stamps >= 0
    if headed.any() and abs(float(np.median(times[headed] - stamps[headed]))) > OTHER_CLOCK_NS:
        headed[:] = False  # stamps on another clock (simulation time): no latency to speak of
    lag = np.where(headed, (times - stamps) / 1e9, 0.0)
    lags, heads = np.r_[0.0, np.cumsum(lag)], np.r_[0, np.cumsum(headed)]
    with np.errstate(divide="ignore", invalid="ignore"):
        latency = np.where(heads[hi] > heads[lo], (lags[hi] - lags[lo]) / (heads[hi] - heads[lo]), np.nan)
    rate = np.where(grid > times[0], count / span, np.nan)  # nothing to divide by at the first message
    bandwidth = np.where(grid > times[0], sent / span, np.nan)
    drops = None
    if seq is not None and len(seq) and bool(np.all(seq >= 0)) and (gaps := seq_gaps(seq[order])) is not None:
        missing = np.r_[0, np.cumsum(gaps)]
        drops = (missing[hi] - missing[lo]).astype(np.float64)  # counted at the message after them
    return TopicHealth(topic, grid, rate, bandwidth, latency, drops)


def bag_health(bag: Bag, start_ns: int | None = None, stop_ns: int | None = None) -> list[TopicHealth]:
    """Every topic's :class:`TopicHealth` over the stretch ``[start_ns, stop_ns)`` (the whole bag by default)."""
    return series(bag, read_messages(bag, start_ns, stop_ns))


def series(bag: Bag, messages: dict[str, tuple[I64, I64, I64, I64]]) -> list[TopicHealth]:
    """Each topic's :class:`TopicHealth` from its messages (:func:`read_messages`)."""
    out = []
    for t, (times, sizes, stamps, seq) in sorted(messages.items()):
        one = bag.topics[t].publishers == 1  # several publishers count each its own
        out.append(health(t, times, sizes, stamps, seq if one else None))
    return out


def messages_base(messages: dict[str, tuple[I64, I64, I64, I64]]) -> TimeBase:
    """The header clock against the receive clock (:func:`~.time_base.header_base`) of the messages with a header."""
    if not messages:
        return header_base(np.zeros(0, np.int64), np.zeros(0, np.int64))
    receive = np.concatenate([m[0] for m in messages.values()])
    return header_base(receive, np.concatenate([m[2] for m in messages.values()]))


class LiveHealth:
    """Each live topic's rate and bandwidth as its messages arrive (source timestamps and sizes), sampled every
    ``period_ns`` up to the time :meth:`add` is told, over the ``window_ns`` before (:func:`health`'s definitions;
    no latency: a live sample's header is not read here). Keeps only the messages a later sample can still count."""

    def __init__(self, *, period_ns: int = PERIOD_NS, window_ns: int = WINDOW_NS) -> None:
        self.period_ns, self.window_ns = period_ns, window_ns
        self._times: dict[str, I64] = {}
        self._sizes: dict[str, I64] = {}
        self._first: dict[str, int] = {}
        self._next: int | None = None

    def add(self, arrivals: Sequence[tuple[str, int, int]], upto_ns: int) -> list[TopicHealth]:
        """``(topic, time, bytes)`` received since the last call; the samples due at or before ``upto_ns``."""
        for topic in {a[0] for a in arrivals}:
            rows = np.array([(t, n) for name, t, n in arrivals if name == topic], np.int64).reshape(-1, 2)
            self._times[topic] = np.r_[self._times.get(topic, np.zeros(0, np.int64)), rows[:, 0]]
            self._sizes[topic] = np.r_[self._sizes.get(topic, np.zeros(0, np.int64)), rows[:, 1]]
            self._first[topic] = min(self._first.get(topic, int(rows[:, 0].min())), int(rows[:, 0].min()))
        if not self._first:
            return []
        start = min(self._first.values()) if self._next is None else self._next
        grid = np.arange(start, upto_ns + 1, self.period_ns, dtype=np.int64)
        if not len(grid):
            return []
        self._next = int(grid[-1]) + self.period_ns
        out = []
        for topic, times in sorted(self._times.items()):
            order = np.argsort(times, kind="stable")
            times, sizes = times[order], self._sizes[topic][order]
            first = self._first[topic]
            g = grid[grid > first]
            if len(g):
                hi = np.searchsorted(times, g, side="right")
                lo = np.searchsorted(times, g - self.window_ns, side="right")
                partial = g - self.window_ns < first  # the first message starts the span
                span = np.minimum(self.window_ns, g - first) / 1e9
                nbytes = np.r_[0, np.cumsum(sizes)]
                first_size = sizes[0] if len(times) and times[0] == first else 0  # (or trimmed)
                rate = (hi - lo - partial) / span
                bandwidth = (nbytes[hi] - nbytes[lo] - np.where(partial, first_size, 0)) / span
                out.append(TopicHealth(topic, g, rate, bandwidth, np.full(len(g), np.nan)))
            keep = times > int(grid[-1]) + self.period_ns - self.window_ns  # what later samples still count
            self._times[topic], self._sizes[topic] = times[keep], sizes[keep]
        return out
