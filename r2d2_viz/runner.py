"""One run of the app: model → source → kinematics → stream, batch or paced to the wall clock.

No rerun import here: the recording is opened and closed by :mod:`r2d2_viz.viewer.sinks` and written by
:mod:`r2d2_viz.viewer.stream` (and, for a bag's recorded transforms, :mod:`r2d2_viz.viewer.tf_recorded`).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path

from r2d2_viz.errors import UsageError
from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.meshes.assets import uri_loader
from r2d2_viz.pacing import Feeds, paced
from r2d2_viz.robot.model import Robot, default_urdf_path
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.xacro_load import is_xacro, load_description, load_robot, read_bounded
from r2d2_viz.signals import sigterm_raises
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.bag_joints import TimeSource
from r2d2_viz.sources.base import Source
from r2d2_viz.sources.motion import ODOM, make_motion
from r2d2_viz.sources.replay import Replay, open_replay
from r2d2_viz.viewer.display_feed import DisplayFeed
from r2d2_viz.viewer.layout.blueprint import generate_blueprint
from r2d2_viz.viewer.layout.plan import plan_view
from r2d2_viz.viewer.notices import Notices
from r2d2_viz.viewer.sinks import SinkConfig, close_recording, open_recording
from r2d2_viz.viewer.stream import RobotStream
from r2d2_viz.viewer.tf_recorded import RecordedTf, TfFeed

BATCH_CHUNK_SAMPLES = 20_000
"""Samples per columnar chunk in batch runs: memory stays flat however long the run."""
BATCH_CHUNK_CELLS = 100_000
"""…and at most this many moving-joint values per chunk, so a robot with thousands of joints stays flat too."""
LIVE_BLOCK_SECONDS = 5.0
"""Live runs compute and encode this much robot time at once (about 1.5 ms of work plus 3 µs a sample), then
send each sample when it is due; the sinks are waited for once a block (backpressure)…"""
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
    realtime: bool = False
    """Pace to the wall clock even when only saving."""
    bag: Path | None = None
    """Replay this ROS 2 bag instead of a generated motion."""
    speed: float = 1.0
    """Replay speed, like ``ros2 bag play --rate``."""
    time: TimeSource = "receive"
    """A bag's times: when each message was received (recorded), or its header stamp."""
    fixed_frame: str | None = None
    rviz: Path | None = None
    """Lay the viewer out as this RViz config does (default: the tutorial's r2d2.rviz, fitted to the robot)."""
    ros: bool = False
    """Join the live ROS 2 graph (:mod:`r2d2_viz.live_run`); ``duration`` is then seconds of wall time."""

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


def run(config: RunConfig, *, on_ready: Callable[[str], None] | None = None) -> RunResult:
    """Run the whole pipeline. Raises R2d2VizError for bad input; never leaves a half-written file."""
    _check_numbers(config)
    if config.ros:
        from r2d2_viz.live_run import run_live

        return RunResult(*run_live(config, on_ready=on_ready))
    with ExitStack() as inputs:
        plan = _plan(config, inputs)
        save = config.sink.save
        if save is not None and save.suffix == ".mcap":
            from r2d2_viz.ros_out.bag_out import write_bag

            with sigterm_raises():
                samples = write_bag(save, plan, plan.description or _description_text(config))
            return RunResult(samples=samples, interrupted=False, saved=save)
        return _record(config, plan, on_ready)


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


def _plan(config: RunConfig, inputs: ExitStack) -> Replay:
    """The robot, its source, recorded transforms and the fixed frame of this run."""
    packages = _packages(config)

    def robot() -> Robot:
        return load_robot(config.urdf or default_urdf_path(), mappings=config.mappings, packages=packages)

    if config.bag is not None:
        bag = inputs.enter_context(open_bag(config.bag))
        replay = open_replay(
            bag,
            load_robot=robot if config.urdf is not None else None,
            time=config.time,
            fixed_frame=config.fixed_frame,
            packages=packages,
        )
        replay.mcap_files = [f for f in bag.files if f.suffix == ".mcap"]
        return replay
    loaded = robot()
    return Replay(compile_tree(loaded), config.source(loaded), None, None, config.fixed_frame or ODOM)


def _record(config: RunConfig, plan: Replay, on_ready: Callable[[str], None] | None) -> RunResult:
    save = config.sink.save
    tmp = _temp_path(save) if save is not None else None
    samples, interrupted = 0, False
    source, tree = plan.source, plan.tree
    clock = source.clock if source is not None else "timestamp"
    view = plan_view(plan, rviz=config.rviz, fixed_frame=config.fixed_frame)
    blueprint = generate_blueprint(view.spec, layout=view.layout)
    try:
        recording = open_recording(config.sink, save_to=tmp, live=config.live, on_ready=on_ready, blueprint=blueprint)
        try:
            rec = recording.rec
            streamer = None
            if tree is not None:
                streamer = RobotStream(
                    rec,
                    tree,
                    frames=source.frames if source is not None else (),
                    clock=clock,
                    fixed_frame=plan.fixed_frame,
                    root_placed=plan.root_placed,
                    axis_length=view.axis_length,
                    show_names=view.show_names,
                )
            notices = streamer.notices if streamer is not None else Notices(rec)
            for note in (*plan.notes, *view.notes):
                notices.report(note)
            recorded = RecordedTf(rec, clock=clock, skip=plan.skip_edges, axis_length=view.axis_length)
            if plan.static_tf is not None:
                recorded.log(plan.static_tf)
            displays = None
            if plan.display_messages is not None:
                displays = DisplayFeed(
                    notices,
                    plan.display_messages(),
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
                    load_mesh=uri_loader(_packages(config), config.bag.parent if config.bag else Path(".")),
                )
            feeds = Feeds(TfFeed(recorded, plan.moving_tf), displays)
            if streamer is not None:
                streamer.log_static()
            if config.live:
                samples, interrupted = paced(streamer, source, feeds, block=_live_block(config), speed=config.speed)
            else:
                with sigterm_raises():
                    samples = _batch(streamer, source, feeds, rec.flush, n_moving=len(tree.moving) if tree else 0)
            _other_topics(plan, config, notices)
            if displays is not None:
                displays.finish()
            if streamer is not None:
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


def _batch(
    streamer: RobotStream | None, source: Source | None, feed: Feeds, flush: Callable[[], None], *, n_moving: int
) -> int:
    """Every sample as fast as the sinks take them, one chunk in flight (memory stays flat)."""
    samples = 0
    if streamer is not None and source is not None:
        for k, chunk in enumerate(source.chunks(batch_chunk_samples(n_moving))):
            prepared = streamer.prepare(chunk)  # meanwhile the sinks write the previous chunk
            if k:
                flush()  # backpressure
            streamer.send(prepared)
            if len(chunk):
                feed.until(int(chunk.times_ns[-1]))
            samples += len(chunk)
    feed.until(None)
    return samples or feed.sent


def _other_topics(plan: Replay, config: RunConfig, notices: Notices) -> None:
    """The bag's topics no display of ours draws: what Rerun's own MCAP decoders show of them (batch runs, .mcap
    storage), and one line naming the rest."""
    skipped = dict(plan.undisplayed)
    if plan.mcap_files and skipped and not config.live:
        from r2d2_viz.viewer.bag_topics import OURS, log_other_topics

        result = log_other_topics(notices.rec, plan.mcap_files, time=config.time, exclude=(*OURS, *plan.displays))
        for topic in result.logged:
            skipped.pop(topic, None)
    if skipped:
        listed = ", ".join(f"{topic} ({msgtype})" for topic, msgtype in sorted(skipped.items()))
        notices.report(f"{config.bag}: topics with no display, not shown: {listed}")


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


def print_summary(result: RunResult, config: RunConfig) -> None:
    where = f" to {result.saved}" if result.saved else ""
    how = " (stopped by signal)" if result.interrupted else ""
    what = f"from {config.bag}" if config.bag is not None else f"at {config.rate:g} Hz"
    what = "of joint states from the ROS 2 graph" if config.ros else what
    print(f"r2d2-viz: {result.samples} samples {what}{where}{how}", file=sys.stderr)
