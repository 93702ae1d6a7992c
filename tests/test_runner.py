"""The runner: how long a run is and how big its chunks are (pacing: tests/test_pacing.py)."""

from __future__ import annotations

import contextlib
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


def test_a_batch_run_waits_for_the_sinks_after_the_arrow_bytes_of_its_samples(tmp_path: Path, monkeypatch) -> None:
    """Issue 38: backpressure counted 64 bytes a robot sample; a robot of many joints hands Rerun a /tf row per joint
    (~60 bytes each) and a plot value, so a run queued many times ``FLUSH_BYTES`` before it waited. The count is now
    the Arrow bytes of the prepared samples: here the first chunk is over ``FLUSH_BYTES`` (1 MB) by itself, so the run
    waits before sending it (64 bytes × 1,800 samples would never have reached 1 MB)."""
    from r2d2_viz import runner
    from r2d2_viz.robot.synth import random_urdf
    from r2d2_viz.viewer.stream import RobotStream

    urdf = tmp_path / "r.urdf"
    urdf.write_text(random_urdf(60, seed=2, joint_types=("revolute",)))
    handed: list[int] = []
    prepare = RobotStream.prepare
    monkeypatch.setattr(
        RobotStream, "prepare", lambda self, chunk: handed.append((p := prepare(self, chunk)).nbytes) or p
    )
    waits: list[int] = []
    monkeypatch.setattr(runner, "flush_file", lambda rec, path: (waits.append(len(handed)), rec.flush()))
    monkeypatch.setattr(runner, "FLUSH_BYTES", 1 << 20)
    monkeypatch.setattr(runner, "FlushAhead", contextlib.nullcontext)  # marks flushed at once: when, not how
    runner.run(RunConfig(urdf=urdf, duration=60.0, rate=30.0, sink=SinkConfig(save=tmp_path / "o.rrd")))
    assert len(handed) == 2 and handed[0] > 1 << 20 > handed[1]  # 1,800 samples of 59 joints: 1,694 + 106
    assert waits == [1]  # before sending the first chunk; the second is under 1 MB
