"""``r2d2-viz --ros``: a live ROS 2 graph into the viewer — the bag replay's pipeline fed by a live source.

The robot comes from ``--urdf`` or the latched ``/robot_description`` (a new description reloads it: the static
scene is logged again; one that does not parse is one line and the run goes on with TF only); ``/joint_states``
goes through the kinematics (:class:`~r2d2_viz.viewer.stream.RobotStream`), ``/tf`` and ``/tf_static`` are
recorded transforms (:class:`~r2d2_viz.viewer.tf_recorded.RecordedTf`), display topics go through
:class:`~r2d2_viz.viewer.display_feed.DisplayFeed` — all as a bag replay does them, on the same ``timestamp``
clock (source timestamps, or header stamps with ``--time header``). ``--save out.rrd`` is finalised when
``--duration`` (wall seconds) runs out or on a signal; ``--save out.mcap`` records what was received.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Protocol

from r2d2_viz.errors import R2d2VizError, listed, shown
from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.live_output import LiveOutput
from r2d2_viz.meshes.assets import uri_loader
from r2d2_viz.msgs.images import EncoderName
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.pacing import LatenessLog
from r2d2_viz.robot.model import Robot, parse_urdf
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.xacro_load import load_robot
from r2d2_viz.ros_out.joint_states_out import live_sliders
from r2d2_viz.ros_out.live_record import LiveBagRecorder
from r2d2_viz.ros_out.tools_out import attach_view_tools, detach_tools
from r2d2_viz.rviz.config import load_rviz, wanted_topics
from r2d2_viz.signals import signals_set
from r2d2_viz.sources.bag_joints import TimeSource
from r2d2_viz.sources.base import tf_root
from r2d2_viz.sources.live.dds import LiveGraph
from r2d2_viz.sources.live.names import EMPTY_GRAPH_HINT, EMPTY_RUN_NEXT, RosDiscovery
from r2d2_viz.sources.live.source import LiveBatch, LiveSource
from r2d2_viz.sources.motion import ODOM
from r2d2_viz.sources.plan import RunPlan
from r2d2_viz.sources.start import live_start_ns
from r2d2_viz.sources.tf_check import urdf_edges
from r2d2_viz.viewer.display_feed import DisplayFeed, VideoFeed
from r2d2_viz.viewer.fields_feed import LiveFields
from r2d2_viz.viewer.files.whole import flush_file
from r2d2_viz.viewer.layout.blueprint import generate_blueprint
from r2d2_viz.viewer.layout.plan import ViewPlan, plan_view, with_telemetry
from r2d2_viz.viewer.notices import Notices
from r2d2_viz.viewer.sinks import Recording, SinkConfig, update_blueprint
from r2d2_viz.viewer.stream import LiveRobots, RobotStream, robot_namespaces
from r2d2_viz.viewer.system.node_graph import NodeGraphLog
from r2d2_viz.viewer.system.tf_graph import TfGraph
from r2d2_viz.viewer.tf_recorded import RecordedTf
from r2d2_viz.viewer.workbench.rviz_axes import start_view

POLL_SECONDS = 0.02
"""At the latest this often, what arrived is taken from the graph and logged (one chunk per entity)…"""
GATHER_SECONDS = 0.002
"""…and as soon as samples arrive, after gathering for this long (a 1 kHz stream: 2 samples a chunk, ms late)."""
SETTLE_SECONDS = 1.5
"""Discovery and the latched topics (``/robot_description``, ``/tf_static``) before the view is planned."""
TF_TOPICS = ("/tf", "/tf_static")
FLUSH_SECONDS = 5.0
"""Wait for the sinks this often (backpressure: a slow sink makes the run lag instead of piling up memory)."""


class LiveConfig(Protocol):
    """What of :class:`r2d2_viz.runner.RunConfig` a live run reads."""

    @property
    def urdf(self) -> Path | None: ...
    @property
    def mappings(self) -> dict[str, str]: ...
    @property
    def package_paths(self) -> tuple[str, ...]: ...
    @property
    def duration(self) -> float | None: ...
    @property
    def sink(self) -> SinkConfig: ...
    @property
    def time(self) -> TimeSource: ...
    @property
    def fixed_frame(self) -> str | None: ...
    @property
    def rviz(self) -> Path | None: ...
    @property
    def tool_topics(self) -> tuple[tuple[str, str], ...]: ...
    @property
    def video(self) -> EncoderName | None: ...
    @property
    def tf_tree(self) -> bool: ...
    @property
    def show(self) -> frozenset[str]: ...
    @property
    def motion(self) -> str | None: ...


def run_live(
    config: LiveConfig,
    *,
    on_ready: Callable[[str], None] | None = None,
    env: Mapping[str, str] | None = None,
) -> tuple[int, bool, Path | None]:
    """Run until ``config.duration`` s pass or a signal; returns (joint states shown, signalled, the file saved)."""
    stop = threading.Event()
    with signals_set(stop), LiveGraph(env) as graph:
        return run_on(config, graph, stop, on_ready)


def run_on(
    config: LiveConfig, graph: LiveGraph, stop: threading.Event, on_ready: Callable[[str], None] | None = None
) -> tuple[int, bool, Path | None]:
    """One live run on ``graph``: settle (discovery, latched topics), plan the view, then hand each batch the graph
    gives to the scene until the deadline or a signal; the files are finalised or, on any failure, removed."""
    deadline = _Deadline(stop, time.monotonic() + config.duration if config.duration is not None else None)
    started = time.monotonic()
    store = typestore(getattr(graph, "distro", "jazzy"))
    source = LiveSource(graph, topics=wanted_topics(config.rviz), time=config.time, known_types=store.fielddefs)
    model = _Model(config)
    batches = _settle(source, model, deadline)
    plan, view = _plan(config, model.robot, batches)
    # the graph's log, diagnostics, fixes and sensors when the view is planned: their views (later ones: below)
    layout = dataclasses.replace(view.layout, tf_graph=config.tf_tree, node_graph=config.tf_tree)
    view = dataclasses.replace(view, layout=with_telemetry(layout, source.display_topics))
    output = LiveOutput(config.sink)
    lateness = LatenessLog.from_env()
    tools = None
    try:
        recording = output.open(view, on_ready)
        sliders = live_sliders(config.motion, model.robot)  # the page's sliders, on /joint_states
        tools = attach_view_tools(recording, view, dict(config.tool_topics), publisher=graph, source=sliders)
        scene = _Scene(config, model, source, view, plan.fixed_frame, recording, lateness, batches)
        if tools is not None and tools.drawing is not None:
            scene.feed.on_map = tools.drawing.cover  # the ground covers the maps
        latest = max((k for k, b in enumerate(batches) if b.descriptions), default=-1)
        for k, batch in enumerate(batches):
            if k < latest:  # a description the settle's latest one replaced: not worth a word
                batch.descriptions.clear()
            scene.handle(batch, output.bag)
        scene.robots.check()
        flushed = time.monotonic()
        while not deadline.done():
            scene.handle(source.poll(), output.bag)
            if (layout := with_telemetry(view.layout, source.display_topics)) != view.layout:  # a new log, …: its view
                view = dataclasses.replace(view, layout=layout)
                update_blueprint(recording, generate_blueprint(view.spec, layout=layout))
            if time.monotonic() - flushed > FLUSH_SECONDS:
                flush_file(recording.rec, output.tmp)  # a full disk: in slices, never for ever (whole.py)
                flushed = time.monotonic()
            if source.graph.wait(POLL_SECONDS):
                time.sleep(GATHER_SECONDS)
        scene.handle(source.poll(), output.bag)  # what came last, and joint states held until the robot was known
        scene.finish()
        _say_received(source, time.monotonic() - started)
        detach_tools(recording, tools)
        output.close()
    except BaseException as exc:
        if output.recording is not None:
            detach_tools(output.recording, tools)
        output.abort(exc)
        raise
    finally:
        lateness.close()
    return scene.samples, stop.is_set(), config.sink.save


@dataclasses.dataclass(frozen=True)
class _Deadline:
    stop: threading.Event
    end: float | None
    """``time.monotonic()`` when ``--duration`` runs out (None: until a signal)."""

    def done(self) -> bool:
        return self.stop.is_set() or (self.end is not None and time.monotonic() >= self.end)


class _Model:
    """The robot model of a live run: ``--urdf``, else the latest ``/robot_description`` that parses."""

    def __init__(self, config: LiveConfig) -> None:
        self.fixed_by_urdf = config.urdf is not None
        self.packages = PackageIndex.from_args(config.package_paths, description=config.urdf, environ=os.environ)
        self.robot: Robot | None = None
        if config.urdf is not None:
            self.robot = load_robot(config.urdf, mappings=config.mappings, packages=self.packages)
        self.description: str | None = None
        """The /robot_description text the robot was built from."""

    def parse(self, text: str, *, quiet: bool = False) -> Robot | None:
        """``text`` as a robot; a bad one raises (None when ``quiet``)."""
        try:
            return parse_urdf(text, source="/robot_description", packages=self.packages)
        except R2d2VizError:
            if not quiet:
                raise
            return None


def _settle(source: LiveSource, model: _Model, deadline: _Deadline) -> list[LiveBatch]:
    """Discovery, the latched description and static transforms: what the view is planned from."""
    batches: list[LiveBatch] = []
    end = time.monotonic() + SETTLE_SECONDS
    while not deadline.done() and time.monotonic() < end:
        batches.append(source.poll())
        if model.robot is None and any(b.descriptions for b in batches):
            text = next(d for b in reversed(batches) for d in reversed(b.descriptions))
            model.robot = model.parse(text, quiet=True)
            model.description = text if model.robot is not None else None
        time.sleep(POLL_SECONDS)
    return batches


def _plan(config: LiveConfig, robot: Robot | None, batches: list[LiveBatch]) -> tuple[RunPlan, ViewPlan]:
    records = [r for b in batches for r in b.tf]
    static = next((r for r in records if r.static), None)
    moving = next((r for r in records if not r.static), None)
    tree = compile_tree(robot) if robot is not None else None
    rviz_frame = load_rviz(config.rviz).fixed_frame if config.rviz is not None else None
    root = tree.robot.root if tree is not None else None
    frame = config.fixed_frame or rviz_frame or tf_root(records) or root or ODOM
    plan = RunPlan(tree, frame, static_tf=static, moving_tf=moving)
    view = plan_view(plan, rviz=config.rviz, fixed_frame=config.fixed_frame, show=config.show)
    if names := robot_namespaces(batches):  # several robots: a plot each, shapes under /robots/<namespace>
        view = dataclasses.replace(view, layout=dataclasses.replace(view.layout, robots=names))
    return plan, view


class _Scene:
    """What a live run shows, batch by batch: the robot (reloaded with each ``/robot_description``), recorded
    transforms, display topics, the notes of the source; with ``--tf-tree``, the TF and node graphs."""

    def __init__(
        self,
        config: LiveConfig,
        model: _Model,
        source: LiveSource,
        view: ViewPlan,
        fixed_frame: str,
        recording: Recording,
        lateness: LatenessLog,
        batches: Sequence[LiveBatch] = (),
    ) -> None:
        rec = recording.rec
        self.model, self.source, self.view, self.fixed_frame, self.rec = model, source, view, fixed_frame, rec
        self.lateness = lateness
        self.children: set[str] = set()
        self.streamer: RobotStream | None = None
        self.samples = 0
        self.notices = Notices(rec, at_ns=live_start_ns(batches), clock="timestamp")  # load-time warnings: first
        start_view(self.notices, view.notes, view.spec, view.layout.fixed_frame or fixed_frame)  # and RViz's Axes
        self.recorded = RecordedTf(rec, clock="timestamp", axis_length=view.axis_length)
        self.recorded.graph = TfGraph(rec, clock="timestamp") if config.tf_tree else None
        self.nodes = NodeGraphLog(rec, clock="timestamp").watch(source if config.tf_tree else None)
        self.feed = DisplayFeed(
            self.notices,
            clock="timestamp",
            fixed_frame=fixed_frame,
            header_time=config.time == "header",
            styles=view.display_styles,
            load_mesh=uri_loader(model.packages, Path(".")),
            video=VideoFeed(config.video, live=True),
        )
        self.fields = LiveFields(rec, typestore(getattr(source.graph, "distro", "jazzy")), config.time == "header")
        self.robots = LiveRobots(self, batches, model.packages, lateness.sent)
        """The namespaced robots (several robots: :class:`r2d2_viz.viewer.stream.LiveRobots`)."""
        if model.robot is not None:
            self._load(model.robot)
        else:
            self.notices.report("no --urdf and no /robot_description yet: transforms only until one is published")

    def _load(self, robot: Robot) -> None:
        tree = compile_tree(robot)
        root_placed = tree.robot.root == self.fixed_frame or tree.robot.root in self.children
        if self.streamer is not None:
            self.streamer.finish()
        self.streamer = RobotStream(
            self.rec,
            tree,
            clock="timestamp",
            fixed_frame=self.fixed_frame,
            root_placed=root_placed,
            axis_length=self.view.axis_length,
            show_names=self.view.show_names,
        )
        self.streamer.notices = self.notices
        self.streamer.log_static(self.view.spec.robot)  # and the RobotModel's mass properties, link axes
        self.recorded.skip = set(urdf_edges(tree)) | self.robots.edges
        self.source.set_joints(tree.actuated)

    def _describe(self, text: str) -> None:
        """A (new) ``/robot_description``: the robot reloaded, or TF only when it does not parse."""
        first = self.model.description is None
        self.model.description = text
        try:
            robot = self.model.parse(text)
        except R2d2VizError as exc:
            self.notices.report(f"{exc} (showing transforms only)", key=f"description {hash(text)}")
            if self.streamer is not None:
                self.streamer.finish()
            self.streamer = None
            self.source.set_joints(None)
            return
        assert robot is not None
        if not first:
            line = f"/robot_description changed: robot {robot.name!r} reloaded"
            self.notices.report(line, key=f"loaded {hash(text)}")
        self.model.robot = robot
        self._load(robot)

    def handle(self, batch: LiveBatch, bag: LiveBagRecorder | None) -> None:
        if bag is not None:
            bag.write(batch.samples)
        self.notices.at_ns = max(self.notices.at_ns, live_start_ns([batch], self.notices.at_ns))  # said: from now
        for key, line in batch.notes:
            self.notices.report(line, key=key)
        if batch.descriptions and not self.model.fixed_by_urdf:
            text = batch.descriptions[-1]
            if text != self.model.description:
                self._describe(text)
        self.robots.describe(batch)
        for records in batch.tf:
            self.children.update(records.children)
            self.recorded.log(records)
        for topic in TF_TOPICS if batch.tf else ():
            self.lateness.sent(topic, (s.source_timestamp_ns for s in batch.samples if s.topic == topic))
        if batch.joints is not None and self.streamer is not None:
            self.streamer.send(self.streamer.prepare(batch.joints))
            self.samples += len(batch.joints)
            self.lateness.sent("/joint_states", batch.joints.times_ns)
        self.samples += self.robots.send(batch)
        self.feed.log(*batch.displays)  # a batch's rows as columns
        for message in batch.displays:
            self.lateness.sent(message.topic, (message.time_ns,))
        self.fields.log(batch.fields)

    def finish(self) -> None:
        for topic, line in self.source.problems():
            self.notices.report(f"{topic}: {line}")
        self.feed.finish()
        self.fields.finish(self.notices.report)
        if self.streamer is not None:
            self.streamer.finish()
        self.robots.finish()
        self.nodes.stop()


def _say_received(source: LiveSource, seconds: float) -> None:
    """The run's last line: each topic's count — or, when nothing came, what was searched and how to check."""
    received = listed(f"{t} {n}" for t, n in sorted(source.received.items()))
    if not received:
        discovery: RosDiscovery | None = getattr(source.graph, "discovery", None)
        where = f" on {discovery.searched()}" if discovery is not None else ""
        print(shown(f"r2d2-viz: received nothing in {seconds:.1f} s{where}"), file=sys.stderr)
        print(f"r2d2-viz: {EMPTY_GRAPH_HINT}; {EMPTY_RUN_NEXT}", file=sys.stderr, flush=True)
        return
    print(shown(f"r2d2-viz: received {received}"), file=sys.stderr, flush=True)
