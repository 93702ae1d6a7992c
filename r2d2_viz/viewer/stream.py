"""Log a robot and its source's samples to Rerun, the way ROS puts them on /tf, /tf_static and
/joint_states. :class:`RobotStream` holds the order of calls in one place:

1. :meth:`RobotStream.log_static` once — warnings of the model, the static scene (:mod:`r2d2_viz.viewer.scene`),
   the moving arrows' style (:mod:`r2d2_viz.viewer.tf_rows`), the plot styles (:mod:`r2d2_viz.viewer.plots`);
2. :meth:`RobotStream.prepare` a chunk of samples — joint state carried forward (:class:`JointState`),
   kinematics, every entity's Arrow columns built once for the whole chunk;
3. :meth:`RobotStream.send` any run of a prepared chunk's samples (all of it in batch runs, sample by
   sample when live): ``/tf`` every time, plots a few times a second, out-of-limit warnings when due;
4. :meth:`RobotStream.finish` — pending plots and the limit lines up to the last sample.

Named frames are the URDF link names plus the fixed frame (``odom``). Quaternions enter Rerun as ``xyzw``.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.arrays import F64, I64
from r2d2_viz.kinematics.tree import KinematicTree, moving_values
from r2d2_viz.sources.base import Clock, JointState, SampleChunk
from r2d2_viz.sources.motion import ODOM
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.columns import Encoded, send, time_array
from r2d2_viz.viewer.layout.fit import AXIS_LENGTH
from r2d2_viz.viewer.notices import Notices, Warn, to_stderr
from r2d2_viz.viewer.plots import JointPlots
from r2d2_viz.viewer.scene import log_scene
from r2d2_viz.viewer.tf_rows import TfRows

PLOT_PERIOD_NS = 500_000_000
"""Live runs send plot values twice a second (each with its own timestamp), transforms every sample."""
LIMIT_LOG_PERIOD_NS = 1_000_000_000
"""How often (in recording time) live runs repeat the constant limit lines, so they span the plot; they
go out with the plot values, so a live sample wakes Rerun's threads once (see :meth:`RobotStream.send`)."""


@dataclass(frozen=True, eq=False)
class _Entity:
    """One entity's columns for a chunk of samples: ``rows`` rows per sample (``/tf`` has one per joint)."""

    path: str
    rows: int
    columns: Encoded
    plot: bool = False
    """Plot data: in live runs sent every ``PLOT_PERIOD_NS`` rather than every sample (see :meth:`send`)."""


@dataclass(frozen=True, eq=False)
class PreparedSamples:
    """Samples encoded for Rerun by :meth:`RobotStream.prepare`: per entity, its Arrow list columns."""

    times_ns: I64  # (n,)
    values: F64  # (n, M) moving-joint values, for the limit checks
    times: dict[int, pa.Array]  # rows per sample → the time column, each sample's time repeated that often
    entities: list[_Entity]
    outside: dict[int, int] = field(default_factory=dict)
    """Moving joint → first sample (an index into ``times_ns``) it is outside its limits, not yet reported."""

    def __len__(self) -> int:
        return len(self.times_ns)


class RobotStream:
    """Logs one robot driven by one source to a recording (see the module docstring for the order of calls).

    ``joints`` and ``frames`` are the source's (:class:`r2d2_viz.sources.base.Source`); ``clock`` says whether
    sample times are durations since the start or timestamps. ``root_placed``: something else (a bag's /tf)
    gives the root its parent frame, so the stream does not pin it to the fixed frame's origin. ``robot_name``: the
    robot's namespace when a run shows several (its shapes and plots under ``/robots/<namespace>/``)."""

    def __init__(
        self,
        rec: rr.RecordingStream,
        tree: KinematicTree,
        *,
        frames: Sequence[tuple[str, str]] = (),
        clock: Clock = "duration",
        fixed_frame: str = ODOM,
        timeline: str = entities.TIMELINE,
        warn: Warn = to_stderr,
        root_placed: bool = False,
        axis_length: float = AXIS_LENGTH,
        show_names: bool = False,
        robot_name: str = "",
        frame_prefix: str = "",
    ) -> None:
        self.rec, self.tree, self.clock, self.timeline = rec, tree, clock, timeline
        self.fixed_frame = fixed_frame
        self.notices = Notices(rec, warn=warn, timeline=timeline)
        self.state = JointState(tree.actuated)
        self.tf = TfRows(tree, tracks=tuple(frames), fixed_frame=fixed_frame)
        self.plots = JointPlots(tree, timeline=timeline, clock=clock, robot=robot_name)
        self.robot_name, self.frame_prefix = robot_name, frame_prefix
        self._root_is_static = not root_placed and not any(child == tree.robot.root for _, child in frames)
        self.axis_length, self.show_names = axis_length, show_names
        self._pending: PreparedSamples | None = None
        self._plot_from = self._sent_to = 0
        self._next_limits_ns: int | None = None
        self._first_ns: int | None = None
        self._last_ns: int | None = None

    # --- 1. static ---------------------------------------------------------------------------------

    def log_static(self) -> None:
        log_scene(
            self.rec,
            self.tree,
            self.notices,
            fixed_frame=self.fixed_frame,
            root_is_static=self._root_is_static,
            axis_length=self.axis_length,
            show_names=self.show_names,
            robot_name=self.robot_name,
            frame_prefix=self.frame_prefix,
        )
        self.tf.log_static(self.rec, entities.TF)
        self.plots.log_styles(self.rec)

    # --- 2. prepare --------------------------------------------------------------------------------

    def prepare(self, chunk: SampleChunk) -> PreparedSamples:
        """Compute and encode a chunk of samples for :meth:`send` (nothing is logged yet).

        Everything is vectorised over the chunk: the Arrow columns are built once, and sending any run
        of its samples later only slices them. Rerun's cost is per chunk sent: a live sample is one
        (``/tf``, arrows included; plots go out a few times a second)."""
        n = len(chunk)
        values = moving_values(self.tree, self.state.update(chunk))
        if n == 0:
            return PreparedSamples(np.zeros(0, dtype=np.int64), values, {}, [])
        if self._first_ns is None:
            self._first_ns = int(chunk.times_ns[0])
        parts: list[_Entity] = []
        if self.tf.rows:
            parts.append(_Entity(entities.TF, self.tf.rows, self.tf.encode(values, chunk.frames)))
        parts.extend(_Entity(entity, 1, columns, plot=True) for entity, columns in self.plots.encode(values))
        times = {r: time_array(np.repeat(chunk.times_ns, r), self.clock) for r in {e.rows for e in parts}}
        return PreparedSamples(chunk.times_ns, values, times, parts, self.plots.outside(values))

    # --- 3. send -----------------------------------------------------------------------------------

    def send(self, samples: PreparedSamples, start: int = 0, stop: int | None = None) -> None:
        """Log samples ``start … stop-1`` of a prepared chunk (all by default), one Rerun chunk per entity.

        Transforms go out with every call. Plot values, when samples come one at a time (live runs), are
        gathered and sent every ``PLOT_PERIOD_NS`` of recording time and when the chunk ends: every value
        keeps its own time, the plot just fills in a few times a second — Rerun's cost is per chunk, and
        this keeps a 30 Hz live run within a few percent of a core."""
        n = len(samples)
        stop = n if stop is None else min(stop, n)
        if start >= stop:
            return
        if samples is not self._pending:
            self._flush_plots()
            self._pending, self._plot_from = samples, start
        for entity in samples.entities:
            if not entity.plot:
                self._send_rows(samples, entity, start, stop)
        self._sent_to = stop
        span = int(samples.times_ns[stop - 1]) - int(samples.times_ns[self._plot_from])
        if stop == n or span >= PLOT_PERIOD_NS:
            self._flush_plots()
        for m, k in samples.outside.items():
            if start <= k < stop:
                self._report_outside(m, samples, k)
        self._last_ns = int(samples.times_ns[stop - 1])

    def _flush_plots(self) -> None:
        """Send the plot values of the samples sent so far that are not plotted yet, and the limit lines:
        at the first sample, then every ``LIMIT_LOG_PERIOD_NS`` (in batch runs: once a chunk)."""
        samples = self._pending
        if samples is None or self._plot_from >= self._sent_to:
            return
        for entity in samples.entities:
            if entity.plot:
                self._send_rows(samples, entity, self._plot_from, self._sent_to)
        self._plot_from = self._sent_to
        last = int(samples.times_ns[self._sent_to - 1])
        if self._next_limits_ns is None or last >= self._next_limits_ns:
            first = self._next_limits_ns is None  # the lines start at the first sample
            self.plots.log_limits(self.rec, self._first_ns if first and self._first_ns is not None else last)
            self._next_limits_ns = last + LIMIT_LOG_PERIOD_NS

    def _send_rows(self, samples: PreparedSamples, entity: _Entity, start: int, stop: int) -> None:
        first, count = start * entity.rows, (stop - start) * entity.rows
        send(self.rec, entity.path, self.timeline, samples.times[entity.rows], entity.columns, first, count)

    def _report_outside(self, m: int, samples: PreparedSamples, k: int) -> None:
        time_ns = int(samples.times_ns[k])
        t_s = (time_ns - (self._first_ns or 0)) * 1e-9
        key = f"limits:{self.tree.moving[m]}"
        if not self.notices.said(key):
            message = self.plots.out_of_limits_message(m, float(samples.values[k, m]), t_s)
            self.notices.report(message, key=key, at_ns=time_ns, clock=self.clock)

    # --- 4. finish ---------------------------------------------------------------------------------

    def finish(self) -> None:
        """Send what is pending and draw the limit lines up to the last sample."""
        self._flush_plots()
        if self._last_ns is not None:
            self.plots.log_limits(self.rec, self._last_ns)


class RobotFeed:
    """Another robot's joint states, sent by its own :class:`RobotStream` in time order as far as a run has got
    (several robots: the first is the run's streamer, the others feeds beside the recorded transforms): a run
    :meth:`push` es each stretch's chunk, and :meth:`until` sends the samples due."""

    def __init__(self, stream: RobotStream) -> None:
        self.stream = stream
        self._pending: deque[tuple[PreparedSamples, int]] = deque()
        self.sent = 0

    def push(self, chunk: SampleChunk | None) -> None:
        if chunk is not None and len(chunk):
            self._pending.append((self.stream.prepare(chunk), 0))

    @property
    def next_time_ns(self) -> int | None:
        if not self._pending:
            return None
        prepared, at = self._pending[0]
        return int(prepared.times_ns[at])

    def until(self, time_ns: int | None = None) -> None:
        """Send the pending samples up to ``time_ns`` (inclusive; all of them when None)."""
        while self._pending:
            prepared, at = self._pending[0]
            n = len(prepared)
            stop = n if time_ns is None else int(np.searchsorted(prepared.times_ns, time_ns, side="right"))
            if stop <= at:
                return
            self.stream.send(prepared, at, stop)
            self.sent += stop - at
            if stop < n:
                self._pending[0] = (prepared, stop)
                return
            self._pending.popleft()
