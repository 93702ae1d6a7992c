"""Topic health in a saved recording (``--tf-tree --save``): one subtree per topic under ``/health``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from rrd import blueprint_components, read_recording
from tfbags import MS, T0, S, bag, edge_every, point, spec, static

from r2d2_viz.viewer.system.health import health_entity


def test_health_series_per_topic(tmp_path: Path) -> None:
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(100) * 50 * MS)  # 20 Hz for 5 s
    for k in range(50):
        s.add("/points", T0 + k * 100 * MS + 30 * MS, point(T0 + k * 100 * MS, "odom"))  # 10 Hz, 30 ms late
    out = tmp_path / "h.rrd"
    done = cli("--bag", str(bag(tmp_path / "b", s)), "--tf-tree", "--save", str(out))
    assert done.returncode == 0, done.stderr
    recording = read_recording(out)
    assert health_entity("/points", "rate") == "/health/points/rate"
    assert {k for k in recording if k.startswith("/health/")} == {
        "/health/points/rate",
        "/health/points/bandwidth",
        "/health/points/latency",
        "/health/tf/rate",
        "/health/tf/bandwidth",
    }
    rate = recording["/health/tf/rate"]
    at_3s = rate.temporal["Scalars:scalars"][rate.times.index(T0 + 3_000_000_000)][0]
    assert at_3s == pytest.approx(20.0)  # by hand: 40 messages in (1 s, 3 s]
    latency = recording["/health/points/latency"].temporal["Scalars:scalars"]
    assert all(v[0] == pytest.approx(0.03) for v in latency)
    views = blueprint_components(out).values()
    assert any(v.get("ViewBlueprint:display_name") == ["Topic rates (Hz)"] for v in views)


def test_ros1_drops_series(tmp_path: Path) -> None:
    """``--tf-tree --save`` on a ROS 1 bag written with rosbags whose ``/temp`` lost slots 5, 6, 7 and 20 (seq as
    rosbags deserialises): ``/health/temp/drops``, by hand 3 in the 2 s up to 1 s, 4 up to 2.5 s, 1 up to 3 s; no
    drops for two publishers (``/pair``) or a type without a header (``/value``)."""
    from seqbags import MS as SMS
    from seqbags import T0 as ST0
    from seqbags import seqs, write

    path = write(tmp_path / "seq.bag")
    assert [s for _, s in seqs(path, "/temp")][4:6] == [104, 108]
    out = tmp_path / "seq.rrd"
    done = cli("--bag", str(path), "--tf-tree", "--save", str(out))
    assert done.returncode == 0, done.stderr
    recording = read_recording(out)
    assert {k for k in recording if k.endswith("/drops")} == {"/health/temp/drops", "/health/ref/drops"}
    drops = recording["/health/temp/drops"]
    at = {(t - ST0) // SMS: v[0] for t, v in zip(drops.times, drops.temporal["Scalars:scalars"], strict=True)}
    assert (at[0], at[1000], at[2500], at[3000]) == (0, 3, 4, 1)


def test_the_bags_last_message_is_in_the_series(tmp_path: Path) -> None:
    """``/points`` every 3 s from 0 to 51 s (the bag's last message), ``/tf`` at 10 Hz to 39.9 s. By hand: the
    points' rate series ends at 51 s, 1 message in (49 s, 51 s] → 0.5 Hz (it ended at 48 s when the stretch read
    stopped before its last message); ``/tf``'s ends at its own last message, 39.9 s."""
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(400) * 100 * MS)
    for k in range(18):
        s.add("/points", T0 + k * 3 * S, point(T0 + k * 3 * S, "odom"))
    out = tmp_path / "h.rrd"
    done = cli("--bag", str(bag(tmp_path / "b", s)), "--tf-tree", "--save", str(out))
    assert done.returncode == 0, done.stderr
    recording = read_recording(out)
    rate = recording["/health/points/rate"]
    assert rate.times[-1] == T0 + 51 * S and rate.temporal["Scalars:scalars"][-1][0] == pytest.approx(0.5)
    assert recording["/health/tf/rate"].times[-1] == T0 + 39_900 * MS


def test_header_time_puts_the_health_and_the_graph_on_the_header_clock(tmp_path: Path) -> None:
    """A simulator's bag: received from T0 (2023), stamped from 1 s after 1970 (``use_sim_time``): ``/tf`` at 10 Hz
    stamped SIM + k·100 ms, ``/points`` received 7 ms after each slot and stamped SIM + k·100 ms, ``/tf_static`` at
    T0. With ``--time header`` the drawings are at the stamps; by hand, the header clock is the receive clock
    shifted by SIM − T0 − 7 ms (the points' offset, the only header), so the points' rate samples fall at
    SIM + j·0.5 s (10 Hz at SIM + 3 s), the static graph snapshot at SIM − 7 ms and the moving ones at SIM + j·0.5 s;
    nothing at the receive times, 53 years away."""
    sim = S
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(50) * 100 * MS, lag_ns=T0 - sim)
    static(s, [("odom", "laser")])
    for k in range(50):
        s.add("/points", T0 + k * 100 * MS + 7 * MS, point(sim + k * 100 * MS, "odom"))
    out = tmp_path / "h.rrd"
    done = cli("--bag", str(bag(tmp_path / "b", s)), "--tf-tree", "--time", "header", "--save", str(out))
    assert done.returncode == 0, done.stderr
    recording = read_recording(out)
    assert recording["/tf"].times[0] == sim and recording["/tf"].times[-1] == sim + 4_900 * MS
    rate = recording["/health/points/rate"]
    assert rate.times[0] == sim + S // 2 and rate.times[-1] == sim + 4_900 * MS
    assert rate.temporal["Scalars:scalars"][rate.times.index(sim + 3 * S)][0] == pytest.approx(10.0)
    graph = recording["/tf_tree"].times
    assert graph[0] == sim - 7 * MS and graph[1:] == list(range(sim, sim + 5 * S, S // 2))
    assert max(t for k, rows in recording.items() if k.startswith(("/health", "/tf")) for t in rows.times) < T0 // 2
