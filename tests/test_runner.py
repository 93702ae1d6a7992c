"""The runner: how long a run is and how big its chunks are (pacing: tests/test_pacing.py)."""

from __future__ import annotations

from pathlib import Path

from r2d2_viz.runner import LAP_SAMPLES, RunConfig, _temp_path, batch_chunk_samples
from r2d2_viz.viewer.sinks import SinkConfig


def test_lengths_and_chunks() -> None:
    assert RunConfig(sink=SinkConfig(save=Path("x.rrd"))).n_samples == LAP_SAMPLES  # one lap by default
    assert RunConfig(sink=SinkConfig(spawn=True)).n_samples is None  # live: until Ctrl-C
    assert RunConfig(duration=2.0, rate=60).n_samples == 120
    assert batch_chunk_samples(3) == 20_000 and batch_chunk_samples(30) * 30 <= 100_000
    assert batch_chunk_samples(10**9) == 1
    assert _temp_path(Path("/d/out.rrd")).parent == Path("/d") and _temp_path(Path("o.rrd")).name.startswith(".o.rrd.")
