"""Log a robot and its source's samples to Rerun, the way ROS puts them on /tf, /tf_static and
/joint_states. :class:`RobotStream` holds the order of calls in one place:

1. :meth:`RobotStream.log_static` once — warnings of the model, the static scene (:mod:`r2d2_viz.viewer.scene`),
   the moving arrows' style (:mod:`r2d2_viz.viewer.tf_rows`), the plot styles (:mod:`r2d2_viz.viewer.plots`);
2. :meth:`RobotStream.prepare` a chunk of samples — joint state carried forward (:class:`JointState`),
   kinematics, every entity's Arrow columns built once for the whole chunk;
3. :meth:`RobotStream.send` any run of a prepared chunk's samples (all of it in batch runs, sample by
   sample when live): ``/tf`` every time (with the plots in a paced save without a live viewer), plots a few
   times a second, out-of-limit warnings when due;
4. :meth:`RobotStream.finish` — pending plots and the limit lines up to the last sample.

Named frames are the URDF link names plus the fixed frame (``odom``). Quaternions enter Rerun as ``xyzw``.

Several robots on a live graph (``r2d2-viz --ros``): :class:`LiveRobots` — every ``/<namespace>/robot_description``
a robot drawn from its description and moved by its ``/<namespace>/joint_states`` by its own :class:`RobotStream`,
its frames prefixed as :func:`r2d2_viz.sources.robots.choose_prefix` says (the root namespace's robot is the run's).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.arrays import F64, I64
from r2d2_viz.errors import R2d2VizError
from r2d2_viz.kinematics.tree import KinematicTree, compile_tree, moving_values
from r2d2_viz.robot.model import parse_urdf
from r2d2_viz.rviz.spec import RobotModel
from r2d2_viz.sources.base import Clock, JointState, SampleChunk
from r2d2_viz.sources.motion import ODOM
from r2d2_viz.sources.robots import RobotPlan, choose_prefix, prefixed_robot, unreached
from r2d2_viz.sources.tf_check import urdf_edges
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.columns import Encoded, send, time_array
from r2d2_viz.viewer.layout.fit import AXIS_LENGTH
from r2d2_viz.viewer.notices import Notices, Warn, to_stderr
from r2d2_viz.viewer.plots import JointPlots
from r2d2_viz.viewer.scene import log_scene
from r2d2_viz.viewer.tf_recorded import RecordedTf
from r2d2_viz.viewer.tf_rows import TfRows
from r2d2_viz.viewer.workbench.mass import log_mass_properties

if TYPE_CHECKING:  # a plain save imports no live source (nor rosbags)
    from r2d2_viz.robot.packages import PackageIndex
    from r2d2_viz.sources.live.source import LiveBatch, LiveSource
    from r2d2_viz.viewer.layout.plan import ViewPlan

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

    @property
    def nbytes(self) -> int:
        """The Arrow bytes of the columns Rerun is handed (what a batch run's backpressure counts)."""
        return int(sum(array.nbytes for entity in self.entities for _, array in entity.columns))


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
        gather: bool = False,
    ) -> None:
        self.rec, self.tree, self.clock, self.timeline = rec, tree, clock, timeline
        self.gather = gather
        """No live viewer (a paced run that only saves): transforms go out with the plot values, every
        ``PLOT_PERIOD_NS``, not every sample — Rerun keeps ~3 kB per chunk in memory for the file's footer until
        the file closes, so a chunk per sample at 1 kHz grew a run by ~75 MB a minute."""
        self.fixed_frame = fixed_frame
        self.notices = Notices(rec, warn=warn, timeline=timeline, clock=clock)
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

    def log_static(self, display: RobotModel | None = None) -> None:
        """The scene, and what ``display`` (a RobotModel display) asks of mass properties and link axes."""
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
        log_mass_properties(self.rec, self.tree.robot, display, self.notices, axis_length=self.axis_length,
                            robot_name=self.robot_name, frame_prefix=self.frame_prefix)  # fmt: skip
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
            if not entity.plot and not self.gather:
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
            if entity.plot or self.gather:
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


# --- several robots on a live graph ---------------------------------------------------------------


class LiveScene(Protocol):
    """What of a live run's scene the robots draw into."""

    rec: rr.RecordingStream
    notices: Notices
    recorded: RecordedTf
    source: LiveSource
    view: ViewPlan
    fixed_frame: str
    children: set[str]


def robot_namespaces(batches: Iterable[LiveBatch]) -> tuple[str, ...]:
    """The namespaces of the robots the settle's ``batches`` described (``""``: ``/robot_description``'s), sorted,
    when there are several; else ``()`` (one robot keeps the single-robot names)."""
    names: set[str] = set()
    for batch in batches:
        names |= {namespace for namespace, _ in batch.robot_descriptions}
        names |= {""} if batch.descriptions else set()
    return tuple(sorted(names)) if len(names) > 1 else ()


class LiveRobots:
    """The namespaced robots of a live run (see the module docstring). ``batches``: what the settle received (which
    robots there are, which frames the graph has); ``sent``: the lateness hook, told of each chunk sent."""

    def __init__(self, scene: LiveScene, batches: Sequence[LiveBatch], packages: PackageIndex,
                 sent: Callable[[str, Iterable[int]], None]) -> None:  # fmt: skip
        self.scene, self.packages, self.sent = scene, packages, sent
        self.several = bool(robot_namespaces(batches))
        self.main: set[str] = set()
        """``{""}`` once ``/robot_description`` (the robot without a namespace) has been described."""
        self.frames = {f for b in batches for r in b.tf for f in (*r.parents, *r.children)}
        self.parents: dict[str, str] = {}
        """Child frame → parent of the transforms received (:meth:`check`)."""
        self.texts: dict[str, str] = {}
        self.streams: dict[str, RobotStream] = {}
        self.plans: dict[str, RobotPlan] = {}
        self.edges: set[tuple[str, str]] = set()
        """The robots' URDF edges: drawn by their kinematics, not as recorded transforms."""

    def describe(self, batch: LiveBatch) -> None:
        """The batch's new namespaced descriptions, each robot (re)loaded."""
        self.main |= {""} if batch.descriptions else set()
        for namespace, text in batch.robot_descriptions:
            if self.texts.get(namespace) != text:
                self._load(namespace, text)

    def _load(self, namespace: str, text: str) -> None:
        """A (new) description of the robot in ``namespace``: (re)loaded, or one line when it does not parse. A second
        robot the settle did not see (a busy machine, a node started later) makes the run one of several robots:
        the robots loaded before it are loaded again under their names."""
        first = namespace not in self.texts
        self.texts[namespace] = text
        if not self.several and len({*self.texts, *self.main}) > 1:
            self.several = True
            for other in [n for n in self.streams if n != namespace]:
                self._build(other, self.texts[other], announce=False)
        self._build(namespace, text, announce=not first)

    def _build(self, namespace: str, text: str, *, announce: bool) -> None:
        scene, topic = self.scene, f"{namespace}/robot_description"
        try:
            robot = parse_urdf(text, source=topic, packages=self.packages)
        except R2d2VizError as exc:
            scene.notices.report(f"{exc} (robot {namespace} not shown)", key=f"description {hash(text)}")
            return
        own_tf = any(f"{namespace}/{name}" in scene.source.subscribed for name in ("tf", "tf_static"))
        prefix = choose_prefix(namespace, robot.root, own_tf=own_tf, frames=self.frames, several=True)
        tree = compile_tree(prefixed_robot(robot, prefix))
        if (old := self.streams.pop(namespace, None)) is not None:
            old.finish()
        if announce:
            scene.notices.report(f"{topic} changed: robot {robot.name!r} reloaded", key=f"loaded {hash(text)}")
        stream = RobotStream(
            scene.rec,
            tree,
            clock="timestamp",
            fixed_frame=scene.fixed_frame,
            root_placed=tree.robot.root == scene.fixed_frame or tree.robot.root in scene.children,
            axis_length=scene.view.axis_length,
            show_names=scene.view.show_names,
            robot_name=namespace if self.several else "",
            frame_prefix=prefix,
        )
        stream.notices = scene.notices
        stream.log_static()
        self.streams[namespace] = stream
        self.plans[namespace] = RobotPlan(namespace, tree, f"{namespace}/joint_states", prefix, text)
        self.edges |= set(urdf_edges(tree))
        scene.recorded.skip |= self.edges
        scene.source.set_joints(tree.actuated, namespace)

    def send(self, batch: LiveBatch) -> int:
        """The batch's namespaced joint states; how many were sent."""
        for records in batch.tf:
            self.parents.update(zip(records.children, records.parents, strict=True))
        count = 0
        for namespace, chunk in batch.robot_joints.items():
            if (stream := self.streams.get(namespace)) is not None:
                stream.send(stream.prepare(chunk))
                count += len(chunk)
                self.sent(f"{namespace}/joint_states", (int(t) for t in chunk.times_ns))
        return count

    def check(self) -> None:
        """One line for each robot (when there are several) whose tree does not reach the fixed frame (said once)."""
        if not self.several:
            return
        for namespace, robot in self.plans.items():
            line = unreached(robot, self.scene.fixed_frame, self.parents)
            if line is not None:
                self.scene.notices.report(line, key=f"unreached {namespace}")

    def finish(self) -> None:
        self.check()
        for stream in self.streams.values():
            stream.finish()
