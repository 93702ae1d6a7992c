"""Live runs paced to the wall clock: robot samples, recorded transforms and display messages, each sent when due.

An absolute schedule, ``start + (t − t₀) / speed`` (no drift; ``start`` is when the first sample is ready, ``t₀``
its time); what falls behind goes out at once, so a late sample does not push the next ones later. Between two
robot samples the recorded transforms and display messages due in between go out at their own times, and after
the robot's last sample the rest keep the same schedule.
"""

from __future__ import annotations

import math
import os
import sys
import threading
import time
from collections.abc import Callable, Iterable
from contextlib import nullcontext
from dataclasses import dataclass, field
from typing import Protocol, TextIO

import numpy as np

from r2d2_viz.signals import signals_set
from r2d2_viz.sources.base import SampleChunk
from r2d2_viz.sources.playback import Window
from r2d2_viz.viewer.display_feed import DisplayFeed
from r2d2_viz.viewer.fields_feed import FieldsFeed
from r2d2_viz.viewer.stream import RobotFeed, RobotStream
from r2d2_viz.viewer.tf_recorded import TfFeed

PACING_LOG_ENV = "R2D2_VIZ_PACING_LOG"
"""Benchmark hook: if set to a path, live runs write one line per sample, ``sample lateness_seconds``
(when its send returned, minus when it was due), and one per hand-over of feed items (recorded TF, display
messages), ``f lateness_seconds`` of the earliest item handed over. Off by default; costs nothing when unset."""
MAX_SLEEP = 0.1
"""Sleep at most this long at a time, so a signal (which sets the stop event) is seen soon."""


class Progress(Protocol):
    """What a live replay tells its progress bar (:mod:`r2d2_viz.progress`): each window when done, and between
    windows where the replay has got (so the bar moves as the bag plays, and stops where a signal stopped it)."""

    def __call__(self, window: Window) -> None: ...
    def at(self, t_ns: int) -> None: ...


class LatenessLog:
    """The benchmark hook (``benchmarks/live_app.py``): when ``R2D2_VIZ_PACING_LOG`` names a file, one line per
    message handed to Rerun, ``topic lateness_seconds`` — the wall time (``time.time()``) when its send returned
    minus its DDS source timestamp (for ``/joint_states`` the chunk's times: header stamps with ``--time header``).
    """

    def __init__(self, file: TextIO | None) -> None:
        self.file = file

    @classmethod
    def from_env(cls) -> LatenessLog:
        path = os.environ.get(PACING_LOG_ENV)
        return cls(open(path, "w", buffering=1 << 16) if path else None)

    def sent(self, topic: str, stamps_ns: Iterable[int]) -> None:
        """``stamps_ns``' messages were just handed to Rerun."""
        if self.file is not None:
            now = time.time()
            self.file.write("".join(f"{topic} {now - int(t) * 1e-9:.6f}\n" for t in stamps_ns))

    def close(self) -> None:
        if self.file is not None:
            self.file.close()


@dataclass
class Feeds:
    """Recorded transforms and display messages, handed on in time order as far as a replay has got."""

    tf: TfFeed
    displays: DisplayFeed | None = None
    robots: list[RobotFeed] = field(default_factory=list)
    """Several robots: the second, third… (the first is the run's streamer)."""
    fields: FieldsFeed | None = None
    """Other topics' fields and ``--plot`` series."""
    reached_ns: int | None = None
    """The end of the last window whose items were handed on (the TF graph's snapshots go on to it)."""

    def push(self, window: Window) -> None:
        """A stretch's transforms and display messages, logged by :meth:`until` when due."""
        self.tf.push(window.tf, (window.joints, *window.more_joints))
        if self.displays is not None:
            self.displays.add_tf(window.tf)
            if window.displays or window.blocks:
                self.displays.push(window.displays, window.blocks)
        for robot, chunk in zip(self.robots, window.more_joints, strict=False):
            robot.push(chunk)
        if self.fields is not None:
            self.fields.push(window.fields)
        self._reached(self.reached_ns)  # the window before: its items were handed on
        self.reached_ns = window.end_ns

    @property
    def next_time_ns(self) -> int | None:
        tf = self.tf.next_time_ns
        shown = self.displays.next_time_ns if self.displays is not None else None
        first = shown if tf is None else tf if shown is None else min(tf, shown)
        feeds: list[RobotFeed | FieldsFeed] = [*self.robots, *([self.fields] if self.fields is not None else [])]
        for robot in feeds:
            t = robot.next_time_ns
            first = t if first is None else first if t is None else min(first, t)
        return first

    def until(self, time_ns: int | None = None) -> None:
        """Hand on what is due by ``time_ns`` (all of it when None: the run has got to its last window's end)."""
        self.tf.until(time_ns)
        if self.displays is not None:
            self.displays.until(time_ns)
        for robot in self.robots:
            robot.until(time_ns)
        if self.fields is not None:
            self.fields.until(time_ns)
        if time_ns is None:
            self._reached(self.reached_ns)

    def _reached(self, time_ns: int | None) -> None:
        """The run has got to ``time_ns``: the TF graph (``--tf-tree``) snapshots up to it, transforms or none."""
        if time_ns is not None and (graph := self.tf.recorded.graph) is not None:
            graph.advance(time_ns)

    @property
    def sent(self) -> int:
        """Transforms and messages handed on so far."""
        return self.tf.logged + (sum(s.messages for s in self.displays.topics.values()) if self.displays else 0)


@dataclass(frozen=True)
class WallClock:
    """Where pacing reads the time and waits: the monotonic clock by default; tests inject a simulated one."""

    now: Callable[[], float] = time.monotonic
    sleep: Callable[[float], None] = time.sleep


@dataclass
class _Clock:
    """The schedule: a time ``t`` (ns) is due at ``start + (t - t0) / speed`` seconds of ``wall.now()``."""

    start: float
    t0: int
    speed: float
    wall: WallClock

    def due(self, t_ns: int) -> float:
        return self.start + (t_ns - self.t0) * (1e-9 / self.speed)

    def now_ns(self) -> int:
        return self.t0 + int((self.wall.now() - self.start) * self.speed * 1e9)


def _feed_until(clock: _Clock, feeds: Feeds, deadline: float, stop: threading.Event, log: TextIO | None = None) -> None:
    """Until ``deadline`` (monotonic seconds), send the feeds' items as each falls due; returns early when nothing
    is pending (the next window may hold more)."""
    while not stop.is_set():
        t = feeds.next_time_ns
        now = clock.wall.now()
        if t is None:
            return
        if clock.due(t) > deadline:
            if deadline > now:
                clock.wall.sleep(min(deadline - now, MAX_SLEEP))
                continue
            return
        if clock.due(t) > now:
            clock.wall.sleep(min(clock.due(t) - now, MAX_SLEEP))
            continue
        feeds.until(max(clock.now_ns(), t))  # t is due: float rounding of now_ns must not hold it back
        if log is not None:
            log.write(f"f {clock.wall.now() - clock.due(t):.6f}\n")


def paced(
    streamer: RobotStream | None,
    windows: Iterable[Window],
    feeds: Feeds,
    *,
    speed: float = 1.0,
    progress: Progress | None = None,
    wall: WallClock | None = None,
    stop: threading.Event | None = None,
    flush: Callable[[], None] | None = None,
) -> tuple[int, bool]:
    """Send each robot sample and every feed item of each window when due on ``wall``, until done or signalled
    (``stop``: set by a signal that came before); returns the samples sent (or, without a robot, the items) and
    whether a signal stopped it. ``progress`` hears where the replay is each time it waits, and where it stopped.
    ``flush`` waits for the sinks once a window (a saved file's: in slices that end a run whose file cannot grow,
    :func:`r2d2_viz.viewer.files.whole.flush_file`; by default the stream's flush)."""
    stop = stop if stop is not None else threading.Event()
    sent = 0
    log_path = os.environ.get(PACING_LOG_ENV)
    clock: _Clock | None = None
    end_ns = 0  # the end of the window being played: the bar does not run ahead of what was read

    def reached() -> None:
        if progress is not None and clock is not None:
            progress.at(min(clock.now_ns(), end_ns))

    wall = _telling(wall or WallClock(), reached)
    with signals_set(stop), open(log_path, "w") if log_path else nullcontext() as log:
        for window in windows:
            feeds.push(window)
            end_ns = window.end_ns
            chunk = window.joints if streamer is not None else None
            if clock is None:  # the schedule starts when the first item is ready to go
                first = [t for t in (feeds.next_time_ns,) if t is not None]
                if chunk is not None and len(chunk):
                    first.append(int(chunk.times_ns[0]))
                if first:
                    clock = _Clock(wall.now(), min(first), speed, wall)
            if clock is None:
                continue
            if streamer is not None and chunk is not None and len(chunk):
                sent += _paced_samples(streamer, chunk, feeds, clock, stop, log, sent)
            if not stop.is_set():
                _feed_until(clock, feeds, clock.due(window.end_ns), stop, log)
            if stop.is_set():
                reached()  # where it stopped, not the end of the window it stopped in
                break
            if progress is not None:
                progress(window)
            if streamer is not None:
                # Backpressure, once a window: wait until the sinks have taken what was sent, so a sink slower
                # than the sample rate makes samples late instead of piling them up in memory.
                (flush or streamer.rec.flush)()
        if not stop.is_set() and clock is not None:
            _feed_until(clock, feeds, math.inf, stop, log)
            feeds.until(None)  # nothing left but the run's end
    return (sent if streamer is not None and sent else feeds.sent), stop.is_set()


def _telling(wall: WallClock, reached: Callable[[], None]) -> WallClock:
    """``wall`` whose every wait ends by calling ``reached``."""

    def sleep(seconds: float) -> None:
        wall.sleep(seconds)
        reached()

    return WallClock(wall.now, sleep)


def _paced_samples(
    streamer: RobotStream,
    chunk: SampleChunk,
    feeds: Feeds,
    clock: _Clock,
    stop: threading.Event,
    log: TextIO | None,
    sent: int,
) -> int:
    """One window's samples, each when due, with the feed items due between them; how many were sent."""
    prepared = streamer.prepare(chunk)
    n = len(chunk)
    due = clock.start + (chunk.times_ns - clock.t0) * (1e-9 / clock.speed)
    i = 0
    while i < n:
        _feed_until(clock, feeds, float(due[i]), stop, log)
        if stop.is_set():
            break
        now = clock.wall.now()
        if due[i] > now:
            clock.wall.sleep(min(float(due[i]) - now, MAX_SLEEP))
            continue
        j = i + 1 + int(np.searchsorted(due[i + 1 :], now, side="right"))
        feeds.until(int(chunk.times_ns[j - 1]))
        streamer.send(prepared, i, j)
        if log is not None:
            done = clock.wall.now()
            log.writelines(f"{sent + k - i} {done - due[k]:.6f}\n" for k in range(i, j))
            if sent == 0 and i == 0:
                log.flush()  # the first sample's line at once: benchmarks time the first data by it
        sent += j - i
        i = j
    return i


def keep_serving(serving: bool, flush: Callable[[], None]) -> None:
    """``--bag BAG --serve`` once the bag has ended (``serving``): the page stays up, its viewer holding the whole
    bag, until Ctrl-C or SIGTERM, as a live run's does."""
    if not serving:
        return
    flush()
    print("r2d2-viz: the bag has ended; still serving until Ctrl-C", file=sys.stderr, flush=True)
    stop = threading.Event()
    with signals_set(stop):
        while not stop.wait(0.5):
            pass
