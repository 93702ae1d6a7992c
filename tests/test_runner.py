"""The runner: how long a run is, how big its chunks are, and live pacing on the wall clock."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from r2d2_viz.runner import LAP_SAMPLES, RunConfig, _paced, _temp_path, batch_chunk_samples
from r2d2_viz.sources.base import ArraySource
from r2d2_viz.viewer.sinks import SinkConfig


def test_lengths_and_chunks() -> None:
    assert RunConfig(sink=SinkConfig(save=Path("x.rrd"))).n_samples == LAP_SAMPLES  # one lap by default
    assert RunConfig(sink=SinkConfig(spawn=True)).n_samples is None  # live: until Ctrl-C
    assert RunConfig(duration=2.0, rate=60).n_samples == 120
    assert batch_chunk_samples(3) == 20_000 and batch_chunk_samples(30) * 30 <= 100_000
    assert batch_chunk_samples(10**9) == 1
    assert _temp_path(Path("/d/out.rrd")).parent == Path("/d") and _temp_path(Path("o.rrd")).name.startswith(".o.rrd.")


class _Recorder:
    """A stand-in for RobotStream that notes when each run of samples was sent."""

    class _Rec:
        def flush(self) -> None:
            pass

    def __init__(self) -> None:
        self.rec = self._Rec()
        self.sent: list[tuple[float, int, int]] = []

    def prepare(self, chunk):
        return chunk

    def send(self, chunk, start: int, stop: int) -> None:
        self.sent.append((time.monotonic(), int(chunk.times_ns[start]), stop - start))


class _NoTf:
    def until(self, time_ns) -> None:
        pass


def test_paced_samples_go_out_in_order_and_not_before_they_are_due() -> None:
    n, period = 12, 0.02
    times = (np.arange(n) * period * 1e9).astype(np.int64)
    source = ArraySource(times, ["j"], np.zeros((n, 1)))
    streamer = _Recorder()
    start = time.monotonic()
    sent, stopped = _paced(streamer, source, _NoTf(), block=5, speed=2.0)  # twice as fast: 10 ms apart
    assert sent == n and not stopped
    assert sum(k for _, _, k in streamer.sent) == n
    assert [t for _, t, _ in streamer.sent] == sorted(t for _, t, _ in streamer.sent)
    first = streamer.sent[0][0]
    for wall, t_ns, _ in streamer.sent:
        assert wall - first >= t_ns * 1e-9 / 2.0 - 1e-3  # never early (1 ms of clock granularity)
    assert time.monotonic() - start >= (n - 1) * period / 2.0 - 1e-3
