"""Where what is measured on receive times goes on a run's timeline. A bag's topic health and the TF graph's clock
are receive times; with ``--time header`` the drawings are at header stamps instead, which a simulator's
``use_sim_time`` puts decades away (a Webots bag: stamps from 0 s, received in 2025). :func:`header_base` follows
the header clock against the receive clock through the bag: per :data:`PERIOD_NS` of receive time, the median of
``stamp − receive`` over the messages with a header received in it (of an even count, the greater of the middle
two; a simulation runs at its own pace: the offset is followed, not fixed once), carried over stretches without
any. Pure numpy; no rerun import."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from r2d2_viz.arrays import I64

PERIOD_NS = 500_000_000


@dataclass(frozen=True)
class TimeBase:
    """Receive time → the run's time: from ``knots_ns[k]`` on (receive times, sorted), ``offsets_ns[k]`` is added;
    none: the identity (a run on receive times)."""

    knots_ns: I64
    offsets_ns: I64

    def __call__(self, receive_ns: I64) -> I64:
        times = np.asarray(receive_ns, np.int64)
        if not len(self.knots_ns):
            return times
        k = np.maximum(np.searchsorted(self.knots_ns, times, side="right") - 1, 0)
        out: I64 = times + self.offsets_ns[k]
        return out

    def at(self, receive_ns: int) -> int:
        return int(self(np.array([receive_ns], np.int64))[0])


RECEIVE = TimeBase(np.zeros(0, np.int64), np.zeros(0, np.int64))


def header_base(receive_ns: I64, stamps_ns: I64, *, period_ns: int = PERIOD_NS) -> TimeBase:
    """The header clock against the receive clock, from messages' receive times and header stamps (those ≤ 0: no
    header, or a stamp never set, left out); :data:`RECEIVE` without any."""
    keep = np.asarray(stamps_ns) > 0
    if not keep.any():
        return RECEIVE
    got = np.asarray(receive_ns, np.int64)[keep]
    offset = np.asarray(stamps_ns, np.int64)[keep] - got
    first = int(got.min())
    bins = (got - first) // period_ns
    order = np.lexsort((offset, bins))
    bins, offset = bins[order], offset[order]
    starts = np.flatnonzero(np.r_[True, bins[1:] != bins[:-1]])
    counts = np.diff(np.r_[starts, len(bins)])
    return TimeBase(first + bins[starts] * period_ns, offset[starts + counts // 2])
