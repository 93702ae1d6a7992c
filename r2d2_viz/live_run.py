"""``r2d2-viz --ros``: a live ROS 2 graph into the viewer — the bag replay's pipeline fed by a live source.

The robot comes from ``--urdf`` or the latched ``/robot_description`` (a new description reloads it: the static
scene is logged again; one that does not parse is one line and the run goes on with TF only); ``/joint_states``
goes through the kinematics (:class:`~r2d2_viz.viewer.stream.RobotStream`), ``/tf`` and ``/tf_static`` are
recorded transforms (:class:`~r2d2_viz.viewer.tf_recorded.RecordedTf`), display topics go through
:class:`~r2d2_viz.viewer.display_feed.DisplayFeed` — all as a bag replay does them, on the same ``timestamp``
clock (the writers' source timestamps, or header stamps with ``--time header``). ``--save out.rrd`` is finalised
when ``--duration`` (seconds of wall time) runs out or on Ctrl-C / SIGTERM; ``--save out.mcap`` records what was
received (:mod:`r2d2_viz.ros_out.live_record`). Only subscribes: nothing is ever published.
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

from r2d2_viz.errors import R2d2VizError
from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.meshes.assets import uri_loader
from r2d2_viz.pacing import LatenessLog
from r2d2_viz.robot.model import Robot, parse_urdf
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.xacro_load import load_robot
from r2d2_viz.ros_out.live_record import LiveBagRecorder
from r2d2_viz.rviz.config import load_rviz
from r2d2_viz.signals import signals_set
from r2d2_viz.sources.bag_joints import TimeSource
from r2d2_viz.sources.base import TfRecords, tf_root
from r2d2_viz.sources.live.dds import LiveGraph
from r2d2_viz.sources.live.source import LiveBatch, LiveSource
from r2d2_viz.sources.motion import ODOM
from r2d2_viz.sources.plan import RunPlan
from r2d2_viz.sources.robots import RobotPlan, choose_prefix, prefixed_robot, unreached
from r2d2_viz.sources.tf_check import urdf_edges
from r2d2_viz.viewer.display_feed import DisplayFeed
from r2d2_viz.viewer.layout.blueprint import generate_blueprint
from r2d2_viz.viewer.layout.plan import ViewPlan, plan_view
from r2d2_viz.viewer.notices import Notices
from r2d2_viz.viewer.sinks import Recording, SinkConfig, close_recording, open_recording
from r2d2_viz.viewer.stream import RobotStream
from r2d2_viz.viewer.tf_recorded import RecordedTf

POLL_SECONDS = 0.02
"""At the latest this often, what arrived is taken from the graph and logged (one chunk per entity)…"""
GATHER_SECONDS = 0.002
"""…and as soon as samples arrive, after gathering for this long (a 1 kHz stream goes out 2 samples a chunk:
lateness of a few ms without a send per sample)."""
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


def run_live(
    config: LiveConfig,
    *,
    on_ready: Callable[[str], None] | None = None,
    env: Mapping[str, str] | None = None,
) -> tuple[int, bool, Path | None]:
    """Run until ``config.duration`` seconds have passed or a signal; returns (joint states shown, whether a
    signal stopped it, the file saved)."""
    stop = threading.Event()
    with signals_set(stop), LiveGraph(env) as graph:
        return _LiveRun(config, graph, stop).run(on_ready)


def wanted_topics(rviz: Path | None) -> set[str] | None:
    """The enabled displays' topics of an RViz config (None without one: every displayable topic)."""
    if rviz is None:
        return None
    return {t.topic for t in load_rviz(rviz).topics if t.enabled and t.topic}


class _LiveRobots:
    """The namespaced robots of a live graph (``/<namespace>/robot_description``), each drawn from its description
    and moved by its ``/<namespace>/joint_states`` by its own :class:`RobotStream`, its frames prefixed as
    :func:`r2d2_viz.sources.robots.choose_prefix` says (the root namespace's robot is :class:`_LiveRun`'s own)."""

    def __init__(self, run: _LiveRun, batches: Sequence[LiveBatch] = ()) -> None:
        """``batches``: what the settle received (which robots there are, which frames the graph has)."""
        self.run = run
        names = {ns for b in batches for ns, _ in b.robot_descriptions}
        names |= {""} if any(b.descriptions for b in batches) else set()
        self.several = len(names) > 1
        self.names = tuple(sorted(names)) if self.several else ()
        """Several robots: their namespaces (a plot each; shapes under ``/robots/<namespace>``)."""
        self.frames = {f for b in batches for r in b.tf for f in (*r.parents, *r.children)}
        self.parents: dict[str, str] = {}
        """Child frame → parent of the transforms received (:meth:`check`)."""
        self.texts: dict[str, str] = {}
        self.streams: dict[str, RobotStream] = {}
        self.plans: dict[str, RobotPlan] = {}
        self.edges: set[tuple[str, str]] = set()

    def laid_out(self, view: ViewPlan) -> ViewPlan:
        """``view`` with a plot per robot, when there are several."""
        if not self.names:
            return view
        return dataclasses.replace(view, layout=dataclasses.replace(view.layout, robots=self.names))

    def describe(self, batch: LiveBatch) -> None:
        for namespace, text in batch.robot_descriptions:
            if self.texts.get(namespace) != text:
                self._load(namespace, text)

    def _load(self, namespace: str, text: str) -> None:
        """A (new) description of the robot in ``namespace``: (re)loaded, or one line when it does not parse."""
        first = namespace not in self.texts
        self.texts[namespace] = text
        run, topic = self.run, f"{namespace}/robot_description"
        try:
            robot = parse_urdf(text, source=topic, packages=run.packages)
        except R2d2VizError as exc:
            run.notices.report(f"{exc} (robot {namespace} not shown)", key=f"description {hash(text)}")
            return
        subscribed = run.source.subscribed
        own_tf = any(f"{namespace}/{name}" in subscribed for name in ("tf", "tf_static"))
        prefix = choose_prefix(namespace, robot.root, own_tf=own_tf, frames=self.frames, several=True)
        tree = compile_tree(prefixed_robot(robot, prefix))
        if (old := self.streams.pop(namespace, None)) is not None:
            old.finish()
        if not first:
            run.notices.report(f"{topic} changed: robot {robot.name!r} reloaded", key=f"loaded {hash(text)}")
        stream = RobotStream(
            run.rec,
            tree,
            clock="timestamp",
            fixed_frame=run.fixed_frame,
            root_placed=tree.robot.root == run.fixed_frame or tree.robot.root in run.children,
            axis_length=run.view.axis_length,
            show_names=run.view.show_names,
            robot_name=namespace if self.several else "",
            frame_prefix=prefix,
        )
        stream.notices = run.notices
        stream.log_static()
        self.streams[namespace] = stream
        self.plans[namespace] = RobotPlan(namespace, tree, f"{namespace}/joint_states", prefix, text)
        self.edges |= set(urdf_edges(tree))
        run.recorded.skip |= self.edges
        run.source.set_joints(tree.actuated, namespace)

    def send(self, batch: LiveBatch) -> int:
        """The batch's namespaced joint states; how many were sent."""
        for records in batch.tf:
            self.parents.update(zip(records.children, records.parents, strict=True))
        sent = 0
        for namespace, chunk in batch.robot_joints.items():
            if (stream := self.streams.get(namespace)) is not None:
                stream.send(stream.prepare(chunk))
                sent += len(chunk)
                self.run.lateness.sent(f"{namespace}/joint_states", chunk.times_ns)
        return sent

    def check(self) -> None:
        """One line for each robot (when there are several) whose tree does not reach the fixed frame (said once)."""
        if not self.several:
            return
        run = self.run
        for namespace, robot in self.plans.items():
            line = unreached(robot, run.fixed_frame, self.parents)
            if line is not None:
                run.notices.report(line, key=f"unreached {namespace}")

    def finish(self) -> None:
        self.check()
        for stream in self.streams.values():
            stream.finish()


class _LiveRun:
    def __init__(self, config: LiveConfig, graph: LiveGraph, stop: threading.Event) -> None:
        self.config, self.stop = config, stop
        self.end = time.monotonic() + config.duration if config.duration is not None else None
        self.source = LiveSource(graph, topics=wanted_topics(config.rviz), time=config.time)
        self.packages = PackageIndex.from_args(config.package_paths, description=config.urdf, environ=os.environ)
        self.robot: Robot | None = None
        if config.urdf is not None:
            self.robot = load_robot(config.urdf, mappings=config.mappings, packages=self.packages)
        self.description: str | None = None
        self.children: set[str] = set()
        self.streamer: RobotStream | None = None
        self.samples = 0
        self.lateness = LatenessLog(None)

    def _done(self) -> bool:
        return self.stop.is_set() or (self.end is not None and time.monotonic() >= self.end)

    def _settle(self) -> list[LiveBatch]:
        """Discovery, the latched description and static transforms: what the view is planned from."""
        batches: list[LiveBatch] = []
        deadline = time.monotonic() + SETTLE_SECONDS
        while not self._done() and time.monotonic() < deadline:
            batches.append(self.source.poll())
            if self.robot is None and any(b.descriptions for b in batches):
                text = next(d for b in reversed(batches) for d in reversed(b.descriptions))
                self.robot = self._parse(text, quiet=True)
                self.description = text if self.robot is not None else None
            time.sleep(POLL_SECONDS)
        return batches

    def _parse(self, text: str, *, quiet: bool = False) -> Robot | None:
        try:
            return parse_urdf(text, source="/robot_description", packages=self.packages)
        except R2d2VizError:
            if not quiet:
                raise
            return None

    def _plan(self, batches: list[LiveBatch]) -> tuple[RunPlan, ViewPlan]:
        records = [r for b in batches for r in b.tf]
        self.robots = _LiveRobots(self, batches)
        static = next((r for r in records if r.static), None)
        moving = next((r for r in records if not r.static), None)
        tree = compile_tree(self.robot) if self.robot is not None else None
        rviz_frame = load_rviz(self.config.rviz).fixed_frame if self.config.rviz is not None else None
        root = tree.robot.root if tree is not None else None
        frame = self.config.fixed_frame or rviz_frame or tf_root(records) or root or ODOM
        plan = RunPlan(tree, frame, static_tf=static, moving_tf=moving)
        view = plan_view(plan, rviz=self.config.rviz, fixed_frame=self.config.fixed_frame)
        view = self.robots.laid_out(view)
        return plan, view

    def run(self, on_ready: Callable[[str], None] | None) -> tuple[int, bool, Path | None]:
        save = self.config.sink.save
        bag_path = save if save is not None and save.suffix == ".mcap" else None
        rrd = save if bag_path is None else None
        sink = self.config.sink
        if bag_path is not None:
            sink = dataclasses.replace(sink, save=None, headless=not sink.live)
        tmp = rrd.with_name(f".{rrd.name}.{os.getpid()}.partial") if rrd is not None else None
        batches = self._settle()
        plan, self.view = self._plan(batches)
        self.fixed_frame = plan.fixed_frame
        blueprint = generate_blueprint(self.view.spec, layout=self.view.layout)
        recording: Recording | None = None
        bag = LiveBagRecorder(bag_path) if bag_path is not None else None
        self.lateness = LatenessLog.from_env()
        try:
            endless = self.end is None or sink.live  # a file without footer: its manifest would grow in memory
            recording = open_recording(sink, save_to=tmp, live=endless, on_ready=on_ready, blueprint=blueprint)
            self._start(recording)
            latest = max((k for k, b in enumerate(batches) if b.descriptions), default=-1)
            for k, batch in enumerate(batches):
                if k < latest:  # a description the settle's latest one replaced: not worth a word
                    batch.descriptions.clear()
                self._handle(batch, bag)
            self.robots.check()
            flushed = time.monotonic()
            while not self._done():
                self._handle(self.source.poll(), bag)
                if time.monotonic() - flushed > FLUSH_SECONDS:
                    recording.rec.flush()
                    flushed = time.monotonic()
                if self.source.graph.wait(POLL_SECONDS):
                    time.sleep(GATHER_SECONDS)
            self._finish()
            close_recording(recording)
            recording = None
            if bag is not None:
                bag.close()
            if tmp is not None and rrd is not None:
                os.replace(tmp, rrd)
        except BaseException:
            if recording is not None:
                close_recording(recording)
            if bag is not None:
                bag.abort()
            if tmp is not None:
                tmp.unlink(missing_ok=True)
            raise
        finally:
            self.lateness.close()
        return self.samples, self.stop.is_set(), save

    def _start(self, recording: Recording) -> None:
        rec = recording.rec
        self.notices = Notices(rec)
        for note in self.view.notes:
            self.notices.report(note)
        self.recorded = RecordedTf(rec, clock="timestamp", axis_length=self.view.axis_length)
        self.feed = DisplayFeed(
            self.notices,
            clock="timestamp",
            fixed_frame=self.fixed_frame,
            header_time=self.config.time == "header",
            styles=self.view.display_styles,
            load_mesh=uri_loader(self.packages, Path(".")),
        )
        self.rec = rec
        if self.robot is not None:
            self._load(self.robot)
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
        self.streamer.log_static()
        self.recorded.skip = set(urdf_edges(tree)) | self.robots.edges
        self.source.set_joints(tree.actuated)

    def _describe(self, text: str) -> None:
        """A (new) ``/robot_description``: the robot reloaded, or TF only when it does not parse."""
        first = self.description is None
        self.description = text
        try:
            robot = self._parse(text)
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
        self.robot = robot
        self._load(robot)

    def _handle(self, batch: LiveBatch, bag: LiveBagRecorder | None) -> None:
        if bag is not None:
            bag.write(batch.samples)
        for key, line in batch.notes:
            self.notices.report(line, key=key)
        if batch.descriptions and self.config.urdf is None:
            text = batch.descriptions[-1]
            if text != self.description:
                self._describe(text)
        self.robots.describe(batch)
        for records in batch.tf:
            self._tf(records)
        for topic in TF_TOPICS if batch.tf else ():
            self.lateness.sent(topic, (s.source_timestamp_ns for s in batch.samples if s.topic == topic))
        if batch.joints is not None and self.streamer is not None:
            self.streamer.send(self.streamer.prepare(batch.joints))
            self.samples += len(batch.joints)
            self.lateness.sent("/joint_states", batch.joints.times_ns)
        self.samples += self.robots.send(batch)
        for message in batch.displays:
            self.feed.log(message)
            self.lateness.sent(message.topic, (message.time_ns,))

    def _tf(self, records: TfRecords) -> None:
        self.children.update(records.children)
        self.recorded.log(records)

    def _finish(self) -> None:
        for topic, line in self.source.problems():
            self.notices.report(f"{topic}: {line}")
        self.feed.finish()
        if self.streamer is not None:
            self.streamer.finish()
        self.robots.finish()
        received = ", ".join(f"{t} {n}" for t, n in sorted(self.source.received.items())) or "nothing"
        print(f"r2d2-viz: received {received}", file=sys.stderr, flush=True)
