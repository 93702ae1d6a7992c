"""Topic health in a saved recording (``--tf-tree --save``): one subtree per topic under ``/health``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from rrd import blueprint_components, read_recording
from tfbags import MS, T0, bag, edge_every, point, spec

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
