"""One run of the app: model → source → kinematics → stream, batch or paced to the wall clock.

No rerun import here: the recording is opened and closed by :mod:`r2d2_viz.sinks` and written by
:mod:`r2d2_viz.stream`.
"""

from __future__ import annotations

import math
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType

import numpy as np

from .errors import UsageError
from .kinematics import compile_tree
from .model import Robot
from .motion import make_motion
from .packages import PackageIndex
from .sinks import SinkConfig, close_recording, open_recording
from .sources import Source
from .stream import RobotStream
from .xacro_load import load_robot

BATCH_CHUNK_SAMPLES = 20_000
"""Samples per columnar chunk in batch runs: memory stays flat however long the run."""
BATCH_CHUNK_CELLS = 1_000_000
"""…and at most this many moving-joint values per chunk, so a robot with thousands of joints stays flat too."""
LIVE_BLOCK_SECONDS = 5.0
"""Live runs compute and encode this much robot time at once (about 1.5 ms of work plus 3 µs a sample), then
send each sample when it is due; the sinks are waited for once a block (backpressure)…"""
LIVE_BLOCK_SAMPLES = 1000
"""…and a block has at most this many samples, so at high rates computing one makes only a sample or two late."""
PACING_LOG_ENV = "R2D2_VIZ_PACING_LOG"
"""Benchmark hook: if set to a path, live runs write one line per sample, ``sample lateness_seconds``
(when its send returned, minus when it was due). Off by default; costs nothing when unset."""
LAP_SAMPLES = 1440
"""One lap of the tutorial's odom circle: 360° / (¼° per sample) — 48 s at the default 30 Hz."""


@dataclass(frozen=True)
class RunConfig:
    urdf: Path
    mappings: dict[str, str] = field(default_factory=dict)
    """xacro arguments (``NAME:=VALUE``)."""
    package_paths: tuple[str, ...] = ()
    """``--package-path DIR|NAME=DIR`` values."""
    motion: str | None = None
    rate: float = 30.0
    duration: float | None = None
    """Seconds of robot time; None: one lap (1,440 samples) for batch saves, forever for live runs."""
    sink: SinkConfig = field(default_factory=SinkConfig)
    realtime: bool = False
    """Pace to the wall clock even when only saving."""

    @property
    def live(self) -> bool:
        return self.sink.live or self.realtime

    @property
    def n_samples(self) -> int | None:
        if self.duration is None:
            return None if self.live else LAP_SAMPLES
        return max(1, round(self.duration * self.rate))

    def source(self, robot: Robot) -> Source:
        """What drives the robot in this run."""
        return make_motion(robot, self.motion, rate=self.rate, n_samples=self.n_samples)


@dataclass
class RunResult:
    samples: int
    interrupted: bool
    saved: Path | None


class _StopRequested(KeyboardInterrupt):  # a signal, not an error
    """Raised in a batch run by SIGTERM so the partial file is removed."""


def run(config: RunConfig, *, on_ready: Callable[[str], None] | None = None) -> RunResult:
    """Run the whole pipeline. Raises R2d2VizError for bad input; never leaves a half-written file."""
    _check_numbers(config)
    packages = PackageIndex.from_args(config.package_paths, description=config.urdf, environ=os.environ)
    robot = load_robot(config.urdf, mappings=config.mappings, packages=packages)
    tree = compile_tree(robot)
    source = config.source(robot)
    save = config.sink.save
    tmp = _temp_path(save) if save is not None else None
    samples = 0
    interrupted = False
    try:
        recording = open_recording(config.sink, save_to=tmp, live=config.live, on_ready=on_ready)
        try:
            streamer = RobotStream(recording.rec, tree, frames=source.frames, clock=source.clock)
            streamer.log_static()
            if config.live:
                block = max(1, min(round(config.rate * LIVE_BLOCK_SECONDS), LIVE_BLOCK_SAMPLES))
                samples, interrupted = _paced(streamer, source, block=block)
            else:
                with _sigterm_raises():
                    for k, chunk in enumerate(source.chunks(batch_chunk_samples(len(tree.moving)))):
                        prepared = streamer.prepare(chunk)  # meanwhile the sinks write the previous chunk
                        if k:
                            recording.rec.flush()  # backpressure: one chunk in flight, memory stays flat
                        streamer.send(prepared)
                        samples += len(chunk)
            streamer.finish()
        finally:
            close_recording(recording)
        if tmp is not None and save is not None:
            os.replace(tmp, save)
    except BaseException:
        if tmp is not None:
            tmp.unlink(missing_ok=True)
        raise
    return RunResult(samples=samples, interrupted=interrupted, saved=save)


def _check_numbers(config: RunConfig) -> None:
    if not (math.isfinite(config.rate) and config.rate > 0):
        raise UsageError(f"--rate must be a positive number of Hz, got {config.rate:g}")
    if config.duration is not None and not (math.isfinite(config.duration) and config.duration > 0):
        raise UsageError(f"--duration must be a positive number of seconds, got {config.duration:g}")
    save = config.sink.save
    if save is not None:
        parent = save.parent if str(save.parent) else Path(".")
        if save.is_dir():
            raise UsageError(f"--save {save}: is a directory; give a file name such as out.rrd")
        if not parent.is_dir():
            raise UsageError(f"--save {save}: directory {str(parent)!r} does not exist")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise UsageError(f"--save {save}: directory {str(parent)!r} is not writable")


def _temp_path(save: Path) -> Path:
    """Beside the target, so the final rename is atomic."""
    return save.with_name(f".{save.name}.{os.getpid()}.partial")


def batch_chunk_samples(n_moving: int) -> int:
    """Samples per chunk of a batch run for a robot with ``n_moving`` moving joints."""
    return max(1, min(BATCH_CHUNK_SAMPLES, BATCH_CHUNK_CELLS // max(1, n_moving)))


def _paced(streamer: RobotStream, source: Source, *, block: int, speed: float = 1.0) -> tuple[int, bool]:
    """Send each sample at ``start + (t - t₀) / speed`` of the wall clock (an absolute schedule: no drift;
    ``start`` is when the first block is ready, ``t₀`` the first sample's time) until done or signalled.

    Samples are computed ``block`` at a time (:meth:`RobotStream.prepare`); each is sent on its own when due.
    If the process falls behind, every sample already due goes out in one send, so a late sample does not
    push the next ones later.
    """
    stop = threading.Event()
    sent = 0
    log_path = os.environ.get(PACING_LOG_ENV)
    with _signals_set(stop), open(log_path, "w") if log_path else nullcontext() as log:
        start = math.nan
        t0 = 0
        for chunk in source.chunks(block):
            prepared = streamer.prepare(chunk)
            n = len(chunk)
            if n == 0:
                continue
            if math.isnan(start):  # the schedule starts when the first sample is ready to go
                start, t0 = time.monotonic(), int(chunk.times_ns[0])
            due = start + (chunk.times_ns - t0) * (1e-9 / speed)
            i = 0
            while i < n:
                delay = due[i] - time.monotonic()
                if delay > 0:  # at most one sample period: a signal's handler sets `stop`, seen right after
                    time.sleep(delay)
                if stop.is_set():
                    break
                j = i + 1 + int(np.searchsorted(due[i + 1 :], time.monotonic(), side="right"))
                streamer.send(prepared, i, j)
                if log is not None:
                    now = time.monotonic()
                    log.writelines(f"{sent + k - i} {now - due[k]:.6f}\n" for k in range(i, j))
                sent += j - i
                i = j
            if i < n:
                break
            # Backpressure, once a block (five seconds): wait until the sinks have taken what was sent, so a
            # sink slower than the sample rate makes samples late instead of piling them up in memory.
            streamer.rec.flush()
    return sent, stop.is_set()


@contextmanager
def _signals_set(stop: threading.Event) -> Iterator[None]:
    """SIGINT and SIGTERM end a live run cleanly (the recording is finalised)."""

    def handler(signum: int, frame: FrameType | None) -> None:
        stop.set()

    with _handlers(handler):
        yield


@contextmanager
def _sigterm_raises() -> Iterator[None]:
    def handler(signum: int, frame: FrameType | None) -> None:
        raise _StopRequested

    with _handlers(handler, signals=(signal.SIGTERM,)):
        yield


@contextmanager
def _handlers(
    handler: Callable[[int, FrameType | None], None],
    signals: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM),
) -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():  # tests may run us in a thread
        yield
        return
    previous = {s: signal.signal(s, handler) for s in signals}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def print_summary(result: RunResult, config: RunConfig) -> None:
    where = f" to {result.saved}" if result.saved else ""
    how = " (stopped by signal)" if result.interrupted else ""
    print(f"r2d2-viz: {result.samples} samples at {config.rate:g} Hz{where}{how}", file=sys.stderr)
