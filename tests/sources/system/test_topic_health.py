"""Each topic's rate, bandwidth and latency over time, by hand on made-up messages and against rosbags' reading of
a crafted bag (receive times, raw sizes, header stamps from its deserialiser)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from tfbags import MS, T0, TS, bag, edge_every, point, spec

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.system.topic_health import bag_health, health

S = 1_000_000_000


def test_by_hand() -> None:
    t = np.arange(0, 5 * S, 100 * MS, dtype=np.int64)  # 10 Hz for 5 s, 50 bytes each, stamped 20 ms before
    h = health("/x", t, np.full(len(t), 50, np.int64), t - 20 * MS)
    at = {int(g): k for k, g in enumerate(h.times_ns)}
    k = at[3 * S]  # window (1 s, 3 s]: 20 messages over 2 s
    assert h.rate_hz[k] == pytest.approx(10.0) and h.bandwidth[k] == pytest.approx(500.0)
    assert h.latency_s[k] == pytest.approx(0.02)
    k = at[S]  # 1 s in: 10 messages after the first, over the 1 s since it came
    assert h.rate_hz[k] == pytest.approx(10.0) and np.isnan(h.rate_hz[at[0]])
    none = health("/y", t, np.full(len(t), 50, np.int64), np.full(len(t), -1, np.int64))
    assert np.isnan(none.latency_s).all()
    sim = health("/z", t + 1_700_000_000 * S, np.full(len(t), 50, np.int64), t)  # sim-time stamps
    assert np.isnan(sim.latency_s).all()


def test_a_crafted_bag_against_rosbags(tmp_path: Path) -> None:
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(100) * 50 * MS)
    for k in range(40):
        s.add("/points", T0 + k * 100 * MS + 7 * MS, point(T0 + k * 100 * MS, "camera"))  # 7 ms late
    path = bag(tmp_path / "b", s)
    with open_bag(path) as b:
        got = {h.topic: h for h in bag_health(b)}
    with AnyReader([path], default_typestore=TS) as reader:
        rows = [(c.topic, t, len(d), reader.deserialize(d, c.msgtype)) for c, t, d in reader.messages()]
    points = [(t, n, m.header.stamp.sec * S + m.header.stamp.nanosec) for topic, t, n, m in rows if topic == "/points"]
    times = np.array([p[0] for p in points])
    sizes = np.array([p[1] for p in points])
    h = got["/points"]
    k = int(np.flatnonzero(h.times_ns == T0 + 3 * S + 7 * MS)[0])
    window = (times > T0 + 1 * S + 7 * MS) & (times <= T0 + 3 * S + 7 * MS)
    assert h.rate_hz[k] == pytest.approx(window.sum() / 2.0)
    assert h.bandwidth[k] == pytest.approx(sizes[window].sum() / 2.0)
    lags = [(t - stamp) / S for t, _, stamp in points]
    assert h.latency_s[k] == pytest.approx(np.mean(np.array(lags)[window]))
    assert np.isnan(got["/tf"].latency_s).all()  # TFMessage has no header of its own


def test_ros1_drops_over_the_window(tmp_path: Path) -> None:
    """``/temp`` at 10 Hz lost slots 5, 6, 7 and 20 (seq 105..107 and 120, as rosbags deserialises around them):
    by hand, the 2 s window up to 1 s holds the message after the first three (3 drops), up to 2.5 s both gaps
    (4), up to 3 s only the last (1); nothing known for two publishers or no header."""
    from seqbags import MS as SMS
    from seqbags import T0 as ST0
    from seqbags import seqs, write

    path = write(tmp_path / "seq.bag")
    got = [s for _, s in seqs(path, "/temp")]
    assert [s for s in range(got[0], got[-1] + 1) if s not in got] == [105, 106, 107, 120]
    with open_bag(path) as b:
        series = {h.topic: h for h in bag_health(b)}
    h = series["/temp"]
    assert h.drops is not None
    at = {int(g - ST0) // SMS: float(d) for g, d in zip(h.times_ns, h.drops, strict=True)}
    assert (at[0], at[500], at[1000], at[2500], at[3000], at[3500]) == (0, 0, 3, 4, 1, 1)
    assert series["/pair"].drops is None and series["/value"].drops is None


def test_drops_by_hand() -> None:
    t = np.arange(0, 5 * S, 100 * MS, dtype=np.int64)
    seq = np.arange(len(t), dtype=np.int64) + 7
    seq[30:] += 2  # two lost before the message at 3 s
    h = health("/x", t, np.full(len(t), 50, np.int64), np.full(len(t), -1, np.int64), seq)
    assert h.drops is not None
    k = int(np.flatnonzero(h.times_ns == 3 * S)[0])
    assert (h.drops[k - 1], h.drops[k], h.drops[k + 3]) == (0, 2, 2)  # windows (0.5, 2.5], (1, 3], (2.5, 4.5] s
    seq[10] = 3  # the count goes back (a restart, or two publishers on one connection): unknown
    assert health("/x", t, np.full(len(t), 50, np.int64), np.full(len(t), -1, np.int64), seq).drops is None


def test_live_health_fed_in_pieces_by_hand() -> None:
    """A live topic at 10 Hz of 100 B from t = 0 for 3 s, and one of a single 50 B message at 1.2 s, given in two
    pieces as a live run's thread gets them. By hand: at 2.5 s the window (0.5, 2.5] holds 20 messages → 10 Hz and
    2000 B / 2 s; at 1 s, 10 messages after the first over 1 s → 10 Hz, 1000 B/s; the lone message has no rate."""
    from r2d2_viz.sources.system.topic_health import LiveHealth

    s = 1_000_000_000
    fast = [("/fast", k * s // 10, 100) for k in range(30)]
    live = LiveHealth()
    first = live.add([*fast[:14], ("/one", 12 * s // 10, 50)], upto_ns=s)  # samples at 0, 0.5, 1 s
    later = live.add(fast[14:], upto_ns=3 * s)
    last = live.add([], upto_ns=4 * s)  # nothing new: /one's message is no longer kept, /fast's last 2 s are
    got = {
        (h.topic, int(t)): (r, b)
        for h in (*first, *later, *last)
        for t, r, b in zip(h.times_ns, h.rate_hz, h.bandwidth, strict=True)
    }
    assert got[("/fast", 7 * s // 2)] == pytest.approx((7.0, 700.0))  # (1.5, 3.5]: 1.6 … 2.9 s, 14 messages
    assert got[("/one", 4 * s)] == pytest.approx((0.0, 0.0))
    assert got[("/fast", s)] == pytest.approx((10.0, 1000.0))
    assert got[("/fast", 5 * s // 2)] == pytest.approx((10.0, 1000.0))
    assert got[("/fast", 3 * s)] == pytest.approx((9.5, 950.0))  # (1, 3]: 19 messages (the last at 2.9 s)
    assert ("/fast", 0) not in got  # nothing to divide by at the first message
    assert got[("/one", 3 * s // 2)] == pytest.approx((0.0, 0.0))  # its first message starts the span: none after
    assert sorted(t for topic, t in got if topic == "/fast") == [k * s // 2 for k in range(1, 9)]


def test_ros1_bandwidth_counts_the_bags_own_bytes(tmp_path: Path) -> None:
    """A ROS 1 ``/clock`` of 8-byte messages every 100 ms (rosbags' writer; its CDR would be 12 bytes): by hand the
    window (3 s, 5 s] holds 20 messages, 160 bytes over 2 s → 80 B/s."""
    from seqbags import T0 as ST0
    from seqbags import write_clock

    with open_bag(write_clock(tmp_path / "clock.bag")) as b:
        (h,) = bag_health(b)
    k = int(np.flatnonzero(h.times_ns == ST0 + 5 * S)[0])
    assert (h.rate_hz[k], h.bandwidth[k]) == (pytest.approx(10.0), pytest.approx(80.0))


def test_latency_of_a_vendors_header_type_and_big_endian_headers(tmp_path: Path) -> None:
    """The bag of ``tests/headerbags.py``: ``/reading`` (a type only the bag defines) received 5 ms after its slot
    and stamped 30 ms before it, ``/points_be`` (big-endian CDR) 6 ms after and 40 ms before: by hand, latencies of
    35 and 46 ms in every window."""
    from headerbags import write

    with open_bag(write(tmp_path / "b")) as b:
        got = {h.topic: h for h in bag_health(b)}
    assert np.allclose(got["/reading"].latency_s, 0.035) and np.allclose(got["/points_be"].latency_s, 0.046)
    assert np.isnan(got["/tf"].latency_s).all()


def test_the_last_message_is_counted() -> None:
    """Messages every 3 s from 0 to 51 s, then a topic of two messages 0.3 s apart. By hand: the first's series
    ends at 51 s with its last message (1 in (49 s, 51 s] → 0.5 Hz); the second's at 0.3 s (1 after the first over
    the 0.3 s since it → 3.33 Hz), off the half-second grid."""
    t = np.arange(18, dtype=np.int64) * 3 * S
    h = health("/slow", t, np.full(len(t), 10, np.int64), np.full(len(t), -1, np.int64))
    assert h.times_ns[-1] == 51 * S and h.rate_hz[-1] == pytest.approx(0.5) and h.bandwidth[-1] == pytest.approx(5)
    two = health("/two", np.array([0, 300 * MS]), np.array([10, 10]), np.array([-1, -1]))
    assert list(two.times_ns) == [0, 300 * MS] and two.rate_hz[-1] == pytest.approx(1 / 0.3)
