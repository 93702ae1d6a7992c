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
