"""The header clock against the receive clock (``--time header``: where receive-time measures go), by hand."""

from __future__ import annotations

import numpy as np

from r2d2_viz.sources.system.time_base import RECEIVE, TimeBase, header_base

S = 1_000_000_000
MS = 1_000_000
T0 = 1_700_000_000 * S


def test_a_simulators_clock_followed_through_the_bag() -> None:
    """Received from T0 every 100 ms for 4 s; stamped by a simulation that starts at 1 s and runs at half speed
    (stamp = 1 s + (receive − T0) / 2), the messages at 0.5, 1.5, 2.5 and 3.5 s stamped 0 (never set: left out).
    By hand: per 0.5 s of receive time from the first message, the offset (stamp − receive) of its middle message
    (of 4, the greater of the two middle offsets: the simulation runs slow, so the earlier message's); a receive
    time maps to itself plus its period's offset (before the first period: the first's; after the last: the
    last's)."""
    receive = T0 + np.arange(40) * 100 * MS
    stamps = S + (receive - T0) // 2
    stamps[5::10] = 0
    base = header_base(receive, stamps)
    assert len(base.knots_ns) == 8 and base.knots_ns[1] == T0 + 500 * MS
    # [1 s, 1.5 s): messages at 1.0 … 1.4 s, the middle one at 1.2 s, stamped 1.6 s
    assert base.at(T0 + 1300 * MS) == T0 + 1300 * MS + (S + 600 * MS - (T0 + 1200 * MS))
    # [0.5 s, 1 s): 0.6 … 0.9 s (0.5 s unset), the middle ones 0.7 and 0.8 s: 0.7 s, stamped 1.35 s
    assert base.at(T0 + 700 * MS) == 1350 * MS
    assert base.at(T0 - 5 * S) == T0 - 5 * S + (S + 100 * MS - (T0 + 200 * MS))  # [0, 0.5 s): 0 … 0.4 s, 0.2 s
    last = base.at(T0 + 60 * S)  # after the last period [3.5 s, 4 s): 3.6 … 3.9 s, 3.7 s stamped 2.85 s
    assert last == T0 + 60 * S + (S + 1850 * MS - (T0 + 3700 * MS))
    assert np.array_equal(base(np.array([T0 + 1300 * MS])), [base.at(T0 + 1300 * MS)])


def test_no_header_no_change() -> None:
    t = np.array([T0, T0 + S])
    assert header_base(t, np.array([-1, 0])) is RECEIVE
    assert np.array_equal(RECEIVE(t), t) and RECEIVE.at(T0) == T0
    assert TimeBase(np.array([T0]), np.array([-T0])).at(T0 + 7) == 7
