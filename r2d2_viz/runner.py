"""One run of the app: model → source → kinematics → stream, batch or paced to the wall clock.

No rerun import here: :mod:`r2d2_viz.viewer.sinks` opens and closes the recording, :mod:`r2d2_viz.viewer` writes it."""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import ExitStack, nullcontext
from dataclasses import dataclass, field
from pathlib import Path

from r2d2_viz.errors import UsageError, shown, warn
from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.meshes.assets import uri_loader
from r2d2_viz.msgs.images import EncoderName
from r2d2_viz.pacing import Feeds, keep_serving, paced
from r2d2_viz.progress import progress_bar
from r2d2_viz.robot.model import Robot, default_urdf_path
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.xacro_load import is_xacro, load_description, load_robot, read_bounded
from r2d2_viz.ros_out.tools_out import attach_view_tools, detach_tools
from r2d2_viz.signals import signals_set, sigterm_raises
from r2d2_viz.sources.bag_joints import TimeSource
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.base import Clock, Source
from r2d2_viz.sources.motion import ODOM, make_motion
from r2d2_viz.sources.plan import BagChoice, RunPlan, plan_bag, plan_motion
from r2d2_viz.sources.playback import LIVE_WINDOW_BYTES, WINDOW_BYTES, Window, read_ahead
from r2d2_viz.sources.robots import SHARED_FRAMES
from r2d2_viz.viewer.display_feed import DisplayFeed, VideoFeed
from r2d2_viz.viewer.fields_feed import FieldsRun, fields_run, undecoded_line
from r2d2_viz.viewer.files.flush_ahead import FLUSH_BYTES, FlushAhead
from r2d2_viz.viewer.files.whole import flush_file, saved_rrd
from r2d2_viz.viewer.layout.blueprint import generate_blueprint
from r2d2_viz.viewer.layout.plan import ViewPlan, joined_topics, plan_view
from r2d2_viz.viewer.notices import run_notices
from r2d2_viz.viewer.sinks import Recording, SinkConfig, close_recording, open_recording
from r2d2_viz.viewer.stream import RobotFeed, RobotStream
from r2d2_viz.viewer.system.health import system_views
from r2d2_viz.viewer.tf_recorded import RecordedTf, TfFeed
from r2d2_viz.viewer.workbench.rviz_axes import start_view
from r2d2_viz.viewer.workbench.watch import watch_robot

BATCH_CHUNK_SAMPLES = 20_000
"""Samples per columnar chunk in batch runs: memory stays flat however long the run."""
BATCH_CHUNK_CELLS = 100_000
"""…and at most this many moving-joint values per chunk, so a robot with thousands of joints stays flat too."""
LIVE_BLOCK_SECONDS = 5.0
"""Live runs compute this much robot time at once, then send each sample when due; sinks waited for once a block…"""
LIVE_BLOCK_SAMPLES = 1000
"""…and a block has at most this many samples, so at high rates computing one makes only a sample or two late."""
LAP_SAMPLES = 1440
"""One lap of the tutorial's odom circle: 360° / (¼° per sample) — 48 s at the default 30 Hz."""


@dataclass(frozen=True)
class RunConfig:
    urdf: Path | None = None
    """URDF or xacro; None: the tutorial's R2D2 — or, replaying a bag, its /robot_description."""
    mappings: dict[str, str] = field(default_factory=dict)
    """xacro arguments (``NAME:=VALUE``)."""
    package_paths: tuple[str, ...] = ()
    """``--package-path DIR|NAME=DIR`` values."""
    motion: str | None = None
    rate: float = 30.0
    duration: float | None = None
    """Seconds of robot time; None: one lap (1,440 samples) for batch saves, forever for live runs."""
    sink: SinkConfig = field(default_factory=SinkConfig)
    realtime: bool = False  # pace to the wall clock even when only saving
    bag: Path | None = None
    """Replay this ROS 2 bag instead of a generated motion."""
    speed: float = 1.0
    """Replay speed, like ``ros2 bag play --rate``."""
    time: TimeSource = "receive"
    """A bag's times: when each message was received (recorded), or its header stamp."""
    fixed_frame: str | None = None
    shared_frames: tuple[str, ...] | None = None
    """Several robots: the frames they share, never prefixed (None: :data:`r2d2_viz.sources.robots.SHARED_FRAMES`)."""
    rviz: Path | None = None
    """Lay the viewer out as this RViz config does (default: the tutorial's r2d2.rviz, fitted to the robot)."""
    ros: bool = False
    """Join the live ROS 2 graph (:mod:`r2d2_viz.live_run`); ``duration`` is then seconds of wall time."""
    start_offset: float = 0.0
    """Seconds into the bag to start at (``ros2 bag play --start-offset``)."""
    topics: tuple[str, ...] | None = None
    """Only these topics of the bag (``ros2 bag play --topics``); None: all."""
    progress: bool = False  # a progress bar on stderr (the CLI sets it on a terminal)
    tool_topics: tuple[tuple[str, str], ...] = ()
    """``--tool-topic``: the page's tools' topics (``2D Goal Pose`` → ``/goal``), over the ``--rviz`` config's."""
    plots: tuple[tuple[str, ...], ...] = ()
    """``--plot`` paths of a bag's fields, one time-series view per flag (:mod:`r2d2_viz.msgs.generic.message_path`)."""
    video: EncoderName | None = None
    """Encode 8-bit camera images as video (``--video``: av1 or h264); None: lossless ``Image`` s."""
    tf_tree: bool = False  # --tf-tree with a sink: the TF tree as a graph view (r2d2_viz/viewer/system/tf_graph.py)
    show: frozenset[str] = frozenset()  # --mass, --inertia, --link-axes: the RobotModel's "mass", "inertia", "axes"
    watch: bool = False  # reload the robot when its files change (r2d2_viz/viewer/workbench/watch.py)

    @property
    def live(self) -> bool:
        return self.sink.live or self.realtime

    @property
    def n_samples(self) -> int | None:
        if self.duration is None:
            return None if self.live else LAP_SAMPLES
        return max(1, round(self.duration * self.rate))

    def source(self, robot: Robot) -> Source:
        """What drives the robot in a run without a bag."""
        return make_motion(robot, self.motion, rate=self.rate, n_samples=self.n_samples)


@dataclass
class RunResult:
    samples: int
    interrupted: bool
    saved: Path | None
    what: str = "samples"  # what ``samples`` counts: a motion's samples, a bag's joint states, or its messages


def run(config: RunConfig, *, on_ready: Callable[[str], None] | None = None) -> RunResult:
    """Run the whole pipeline. Raises R2d2VizError for bad input; never leaves a half-written file."""
    _check_numbers(config)
    if config.ros:
        from r2d2_viz.live_run import run_live

        return RunResult(*run_live(config, on_ready=on_ready))
    with ExitStack() as inputs:
        plan = _plan(config, inputs)
        save = config.sink.save
        if save is not None and save.suffix == ".mcap" and plan.replay is not None and _ros1(plan.replay.bag.files):
            from r2d2_viz.ros_out.bag_convert import convert_bag

            with sigterm_raises():
                written = convert_bag(plan.replay.bag, save)
            return RunResult(samples=written, interrupted=False, saved=save, what="messages converted")
        if save is not None and save.suffix == ".mcap":
            from r2d2_viz.ros_out.bag_out import write_bag

            if len(plan.robots) > 1:
                warn(f"{config.bag}: several robots: {save} holds only the first, {plan.robots[0].name}")
            with sigterm_raises():
                samples = write_bag(save, plan, plan.description or _description_text(config))
            return RunResult(samples=samples, interrupted=False, saved=save)
        result = _record(config, plan, on_ready)
        result.what = _counted(config, plan, result.samples)
        return result


def _ros1(files: tuple[Path, ...]) -> bool:
    return any(f.suffix == ".bag" for f in files)


def _counted(config: RunConfig, plan: RunPlan, samples: int) -> str:
    """What a run without ``--ros`` counted: the robot's samples when some moved it, else the messages handed on."""
    if config.bag is None:
        return "samples"
    return "joint states" if plan.moves_robot and samples else "transforms and display messages"


def _packages(config: RunConfig) -> PackageIndex:
    description = config.urdf or (None if config.bag is not None else default_urdf_path())
    return PackageIndex.from_args(config.package_paths, description=description, environ=os.environ)


def _description_text(config: RunConfig) -> str:
    """The URDF a bag's /robot_description carries: the file, or what its xacro expands to."""
    path = config.urdf or default_urdf_path()
    data = read_bounded(path)
    if is_xacro(path, data):
        return load_description(path, mappings=config.mappings, packages=_packages(config)).text.decode("utf-8")
    return data.decode("utf-8")


def _plan(config: RunConfig, inputs: ExitStack) -> RunPlan:
    """The robot, its source, recorded transforms and the fixed frame of this run."""
    packages = _packages(config)

    def robot() -> Robot:
        return load_robot(config.urdf or default_urdf_path(), mappings=config.mappings, packages=packages)

    if config.bag is not None:
        bag = inputs.enter_context(open_bag(config.bag))
        return plan_bag(
            bag,
            load_robot=robot if config.urdf is not None else None,
            time=config.time,
            fixed_frame=config.fixed_frame,
            packages=packages,
            choice=BagChoice(config.start_offset, config.duration, config.topics, joined_topics(config.rviz)),
            shared_frames=config.shared_frames or SHARED_FRAMES,
        )
    loaded = robot()
    return plan_motion(compile_tree(loaded), config.source(loaded), config.fixed_frame or ODOM)


def _record(config: RunConfig, plan: RunPlan, on_ready: Callable[[str], None] | None) -> RunResult:
    tmp = _temp_path(save) if (save := config.sink.save) is not None else None
    samples, interrupted, tree = 0, False, plan.tree
    clock: Clock = plan.source.clock if plan.source is not None else "timestamp"
    view = plan_view(plan, rviz=config.rviz, fixed_frame=config.fixed_frame, show=config.show)
    fields = fields_run(plan, config.plots, clock, header_time=config.time == "header", gather=not config.live)
    layout = dataclasses.replace(view.layout, field_plots=config.plots, tf_graph=config.tf_tree)
    view = dataclasses.replace(view, layout=layout)
    blueprint = generate_blueprint(view.spec, layout=view.layout)
    stop = threading.Event()  # live: a signal that comes before the pacing (the viewer told where to look) stops too
    with saved_rrd(tmp, save), signals_set(stop) if config.live else nullcontext(), ExitStack() as ends:
        recording = open_recording(config.sink, save_to=tmp, on_ready=on_ready, blueprint=blueprint)
        tools = attach_view_tools(recording, view, dict(config.tool_topics), source=plan.source)
        try:
            rec, flush = recording.rec, lambda: flush_file(recording.rec, tmp)  # a full disk ends the run
            gather = config.realtime and not config.sink.live  # saved only: no viewer waits for each sample
            streamers = _robot_streams(recording, plan, view, clock, gather) if tree is not None else []
            streamer = streamers[0] if streamers else None
            notices = run_notices(rec, plan, clock, streamers)  # untimed warnings at the run's first time
            start_view(notices, (*plan.notes, *view.notes), view.spec, view.layout.fixed_frame or plan.fixed_frame)
            recorded = RecordedTf(rec, clock=clock, skip=set(plan.skip_edges), axis_length=view.axis_length)
            recorded.graph = system_views(rec, clock, plan.replay) if config.tf_tree else None
            if plan.static_tf is not None:
                recorded.log(plan.static_tf)
            displays = None
            if plan.displays:
                displays = DisplayFeed(
                    notices,
                    clock=clock,
                    fixed_frame=plan.fixed_frame,
                    header_time=config.time == "header",
                    styles=view.display_styles,
                    source_name=str(config.bag),
                    topics=plan.displays,
                    start_ns=int(plan.moving_tf.times_ns.min())
                    if plan.moving_tf is not None and len(plan.moving_tf)
                    else None,
                    tf=[r for r in (plan.static_tf, plan.moving_tf) if r is not None],
                    video=VideoFeed(config.video, live=config.live),
                    hold=not config.live,  # runs of display columns kept across windows (fewer, bigger chunks)
                    load_mesh=uri_loader(_packages(config), config.bag.parent if config.bag else Path(".")),
                )
                displays.on_map = tools.drawing.cover if tools and tools.drawing else None  # the ground: over maps
                displays.push(plan.seek_messages)
            feeds = Feeds(
                TfFeed(recorded, plan), displays, [*map(RobotFeed, streamers[1:])], fields.feed(rec) if fields else None
            )
            watching = config.watch and watch_robot(recording, plan.source, streamer, config, _packages(config), ends)
            for robot in streamers:
                (watching or robot).log_static(view.spec.robot)
            with progress_bar(plan, config) as shown:
                windows = _windows(plan, config, displays, fields)
                if config.live:
                    samples, interrupted = paced(
                        streamer, windows, feeds, speed=config.speed, progress=shown, stop=stop, flush=flush
                    )
                else:
                    with sigterm_raises(), FlushAhead(flush) as ahead:  # a mark waits for the previous one's flush
                        samples = _batch(streamer, windows, feeds, ahead, shown)
            keep_serving(config.sink.serve and config.bag is not None and not interrupted, flush)
            if line := undecoded_line(plan.undisplayed, fields):  # no display, and fields not decodable either
                notices.report(f"{config.bag}: {line}")
            if feeds.fields is not None:
                feeds.fields.finish(notices.report)
            if displays is not None:
                displays.finish()
            for robot in streamers:
                robot.finish()
        finally:
            detach_tools(recording, tools)
            close_recording(recording)
    return RunResult(samples=samples, interrupted=interrupted, saved=save)


def _robot_streams(
    recording: Recording, plan: RunPlan, view: ViewPlan, clock: Clock, gather: bool = False
) -> list[RobotStream]:
    """A stream per robot: the plan's one, or each of several (shapes and plots under ``/robots/<namespace>/``)."""
    rec = recording.rec
    if plan.tree is None:
        return []
    if not plan.robots:
        return [
            RobotStream(
                rec,
                plan.tree,
                frames=plan.source.frames if plan.source is not None else (),
                clock=clock,
                fixed_frame=plan.fixed_frame,
                root_placed=plan.root_placed,
                axis_length=view.axis_length,
                show_names=view.show_names,
                gather=gather,
            )
        ]
    several = len(plan.robots) > 1
    return [
        RobotStream(
            rec,
            robot.tree,
            clock=clock,
            fixed_frame=plan.fixed_frame,
            root_placed=plan.placed(robot.tree.robot.root),
            axis_length=view.axis_length,
            show_names=view.show_names,
            robot_name=robot.namespace if several else "",
            frame_prefix=robot.prefix,
            gather=gather,
        )
        for robot in plan.robots
    ]


def _windows(
    plan: RunPlan, config: RunConfig, displays: DisplayFeed | None, fields: FieldsRun | None
) -> Iterator[Window]:
    """The run's windows; a bag's read and decoded ahead in a thread (beside the recording's writing)."""
    if config.live:
        size = _live_block(config)
    else:
        size = batch_chunk_samples(len(plan.tree.moving) if plan.tree is not None else 0)
    windows = plan.windows(
        size,
        predecode=displays.decode if displays is not None else None,
        max_bytes=LIVE_WINDOW_BYTES if config.live else WINDOW_BYTES,
        **({"fields": fields.decoding} if fields is not None else {}),
    )
    return read_ahead(windows) if plan.replay is not None else windows


def _batch(
    streamer: RobotStream | None,
    windows: Iterator[Window],
    feed: Feeds,
    flush: Callable[[], None],
    progress: Callable[[Window], None] | None,
) -> int:
    """Every window as fast as the sinks take them, a bounded amount in flight (memory stays flat)."""
    samples = unflushed = 0
    for window in windows:
        chunk = window.joints if streamer is not None else None
        prepared = streamer.prepare(chunk) if streamer is not None and chunk is not None and len(chunk) else None
        unflushed += window.nbytes + (prepared.nbytes if prepared is not None else 0)
        if unflushed > FLUSH_BYTES:  # backpressure: the sinks have taken what came before the previous mark
            flush()
            unflushed = 0
        if streamer is not None and prepared is not None and chunk is not None:
            streamer.send(prepared)
            samples += len(chunk)
        feed.push(window)
        feed.until(window.end_ns)
        if progress is not None:
            progress(window)
    feed.until(None)
    return (samples + sum(r.sent for r in feed.robots)) or feed.sent


def _live_block(config: RunConfig) -> int:
    rate = config.rate if config.bag is None else 100.0  # a bag's rate is its own: blocks of about a second
    return max(1, min(round(rate * LIVE_BLOCK_SECONDS), LIVE_BLOCK_SAMPLES))


def _check_numbers(config: RunConfig) -> None:
    if not (math.isfinite(config.rate) and config.rate > 0):
        raise UsageError(f"--rate must be a positive number of Hz, got {config.rate:g}")
    if config.duration is not None and not (math.isfinite(config.duration) and config.duration > 0):
        raise UsageError(f"--duration must be a positive number of seconds, got {config.duration:g}")
    save = config.sink.save
    if save is not None:
        parent = save.parent if str(save.parent) else Path(".")
        if save.is_dir() and save.suffix == ".mcap":
            from r2d2_viz.ros_out.bag_write import written_by_us

            if not written_by_us(save):  # a bag r2d2-viz wrote is replaced, as an .rrd is; nothing else
                raise UsageError(f"--save {save}: a directory that is not a bag r2d2-viz wrote; not replacing it")
        elif save.is_dir():
            raise UsageError(f"--save {save}: is a directory; give a file name such as out.rrd")
        if not parent.is_dir():
            raise UsageError(f"--save {save}: directory {str(parent)!r} does not exist")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise UsageError(f"--save {save}: directory {str(parent)!r} is not writable")


def _temp_path(save: Path) -> Path:  # beside the target, so that the final rename is atomic
    return save.with_name(f".{save.name}.{os.getpid()}.partial")


def batch_chunk_samples(n_moving: int) -> int:
    """Samples per chunk of a batch run for a robot with ``n_moving`` moving joints."""
    return max(1, min(BATCH_CHUNK_SAMPLES, BATCH_CHUNK_CELLS // max(1, n_moving)))


def print_summary(result: RunResult, config: RunConfig) -> None:
    where = f" to {result.saved}" if result.saved else ""
    how = " (stopped by signal)" if result.interrupted else ""
    origin = "from the ROS 2 graph" if config.ros else f"from {config.bag}" if config.bag else f"at {config.rate:g} Hz"
    what = "joint states" if config.ros else result.what
    print(shown(f"r2d2-viz: {result.samples} {what} {origin}{where}{how}"), file=sys.stderr)
