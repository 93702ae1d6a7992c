"""``--watch``: reload the robot in place when its description, a file xacro read or a mesh changes.

:func:`watch_robot` hooks a generated motion (:attr:`GeneratedMotion.before_chunk`): before each sample, the
poller (:class:`r2d2_viz.robot.watch.FileWatcher`) is asked whether the files changed; if so the robot is loaded
again, the motion and the run's :class:`RobotStream` re-made for it in place (the time line goes on), the new scene
logged at the sample's time, and the entities of links that are gone cleared. The scene is logged on the time line
(not static, as without ``--watch``): static data would hide what a reload logs. A broken edit is one line on stderr
and on ``/warnings`` at the run's time; the last good robot stays.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable, Iterable, Mapping
from contextlib import ExitStack
from pathlib import Path
from typing import Any, Protocol, cast

import numpy as np
import rerun as rr

from r2d2_viz.errors import R2d2VizError, UsageError, shown_in_line
from r2d2_viz.kinematics.tree import KinematicTree, compile_tree
from r2d2_viz.robot.model import Robot, default_urdf_path
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.watch import FileWatcher, Loading, robot_files
from r2d2_viz.robot.xacro_load import XacroCancelledError, load_robot
from r2d2_viz.rviz.spec import RobotModel
from r2d2_viz.sources.base import Source
from r2d2_viz.sources.motion import GeneratedMotion, SlidersMotion
from r2d2_viz.sources.sliders import SliderBoard
from r2d2_viz.viewer.sinks import Recording
from r2d2_viz.viewer.stream import RobotStream


class Poller(Protocol):
    def watch(self, files: Iterable[Path]) -> None: ...
    def changed(self) -> bool: ...


PollerFactory = Callable[[tuple[Path, ...]], Poller]
_KEPT = ("notices", "_first_ns", "_next_limits_ns", "_last_ns")
"""What a re-made stream keeps of the old one: its notices said, and where the time line is."""


class _Timed:
    """A recording whose ``log(..., static=True)`` logs at ``at_ns`` on the time line instead, noting each entity."""

    def __init__(self, rec: rr.RecordingStream, timeline: str, clock: str) -> None:
        self.rec, self.timeline, self.clock = rec, timeline, clock
        self.at_ns = 0
        self.logged: set[str] = set()

    def log(self, entity: str, *archetypes: Any, static: bool = False, **kwargs: Any) -> None:
        if self.clock == "duration":
            self.rec.set_time(self.timeline, duration=np.timedelta64(self.at_ns, "ns"))
        else:
            self.rec.set_time(self.timeline, timestamp=np.datetime64(self.at_ns, "ns"))
        self.logged.add(entity)
        self.rec.log(entity, *archetypes, **kwargs)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.rec, name)


Load = Callable[[list[Path], threading.Event | None], Robot]
"""Loads the description (the files xacro read go into the list; the event, when set, stops xacro at once)."""


class Watching:
    """One watched robot: the run's stream and motion, re-made on each good edit.

    In a live run (``background``) the edited robot is loaded in a thread (:class:`Loading`): the run goes on with
    the robot it has, and the new one is shown at the first sample after it loaded. :meth:`close` stops a load in
    flight (its xacro child killed at once)."""

    def __init__(
        self,
        stream: RobotStream,
        motion: GeneratedMotion,
        description: Path,
        load: Load,
        poller: PollerFactory,
        page_config: dict[str, Any] | None = None,
        *,
        background: bool = False,
    ) -> None:
        self.stream, self.motion, self.description, self.load = stream, motion, description, load
        self.page_config = page_config
        """``--serve``'s page configuration: its sliders are the new robot's once the page is reloaded."""
        self.background = background
        self.timed = _Timed(stream.rec, stream.timeline, stream.clock)
        self.display: RobotModel | None = None
        self.loading: Loading[tuple[Robot, KinematicTree]] | None = None
        """A reload's load in flight (live runs)."""
        self.first: Loading[tuple[Robot, KinematicTree]] | None = None
        """A live run's first load, only to learn which files xacro reads (in a thread too: it may be slow)."""
        read: list[Path] = []
        if background:
            self.first = self.loading = Loading(self._load_tree)
        else:
            self._xacro_files(read)
        self.files = robot_files(description, stream.tree.robot, read)
        self.poller = poller(self.files)
        self.reloads = 0
        motion.before_chunk = self.before_chunk

    def _xacro_files(self, read: list[Path]) -> None:
        try:
            self.load(read, None)
        except R2d2VizError:
            pass

    def _load_tree(self, read: list[Path], cancel: threading.Event) -> tuple[Robot, KinematicTree]:
        robot = self.load(read, cancel)
        return robot, compile_tree(robot)

    def close(self) -> None:
        """The run ends: a load in flight is stopped (its xacro child killed), not waited for."""
        loading, self.loading = self.loading, None
        if loading is not None:
            loading.stop()

    def log_static(self, display: RobotModel | None = None) -> None:
        """The scene, on the time line at the first sample (what :meth:`RobotStream.log_static` logs static)."""
        self.display = display
        self._log_scene(0)

    def _log_scene(self, at_ns: int) -> set[str]:
        self.timed.at_ns, self.timed.logged = at_ns, set()
        real, timed = self.stream.rec, cast(rr.RecordingStream, self.timed)
        self.stream.rec, self.stream.notices.at_ns = timed, at_ns  # the model's warnings too: at the reload's time
        try:
            self.stream.log_static(self.display)
        finally:
            self.stream.rec = real
            real.reset_time()
        return self.timed.logged

    def before_chunk(self, k: int) -> None:
        if self.loading is None and self.poller.changed():
            self.loading = Loading(self._load_tree)
        if self.loading is not None and (self.loading.done or not self.background):  # batch: waited for
            loading, self.loading = self.loading, None
            if loading is self.first:  # what xacro read: watched from now on (an edit meanwhile is seen next)
                self.files = tuple(sorted({*self.files, *robot_files(self.description, None, loading.read)}))
                self.poller.watch(self.files)
            else:
                self._shown(k, loading)

    def reload(self, k: int) -> bool:
        """Load the robot again for sample ``k`` (waiting for it); True if it loaded (else one line, and the robot
        stays)."""
        return self._shown(k, Loading(self._load_tree))

    def _shown(self, k: int, loading: Loading[tuple[Robot, KinematicTree]]) -> bool:
        """The load's robot shown from sample ``k`` on (waiting for it); or its error, one line."""
        at_ns = int(np.rint(k * (1e9 / self.motion.rate)))
        read = loading.read
        try:
            robot, tree = loading.outcome()
        except XacroCancelledError:
            return False
        except R2d2VizError as exc:
            self.poller.watch(sorted({*self.files, *robot_files(self.description, None, read)}))
            message = f"{exc} (--watch: the last good robot stays)"
            self.stream.notices.report(message, key=f"watch:{at_ns}", at_ns=at_ns, clock=self.stream.clock)
            return False
        before = self.timed.logged
        self._remake(robot, tree)
        gone = before - self._log_scene(at_ns)
        self.timed.at_ns = at_ns
        for entity in sorted(gone):
            self.timed.log(entity, rr.Clear(recursive=False))
        self.stream.rec.reset_time()
        self.files = robot_files(self.description, robot, read)
        self.poller.watch(self.files)
        self.reloads += 1
        links = f"{len(robot.links)} link{'s' if len(robot.links) != 1 else ''}"
        print(shown_in_line(f"r2d2-viz: reloaded {self.description.name}: {links}"), file=sys.stderr, flush=True)
        return True

    def _remake(self, robot: Robot, tree: Any) -> None:
        motion, old = self.motion, self.stream
        board = motion.board if isinstance(motion, SlidersMotion) else None
        hook = motion.before_chunk
        type(motion).__init__(motion, robot, rate=motion.rate, n_samples=motion.n_samples)
        motion.before_chunk = hook
        if board is not None and isinstance(motion, SlidersMotion):  # the page's handler holds the old board
            fresh: SliderBoard = motion.board
            vars(board).update({k: v for k, v in vars(fresh).items() if k != "_lock"})
            motion.board = board
            if self.page_config is not None and "joints" in self.page_config:
                self.page_config.update(joints=board.describe())
        old.finish()  # the old robot's pending plot values
        new = RobotStream(
            old.rec,
            tree,
            frames=motion.frames,
            clock=old.clock,
            fixed_frame=old.fixed_frame,
            timeline=old.timeline,
            warn=old.notices.warn,
            axis_length=old.axis_length,
            show_names=old.show_names,
            robot_name=old.robot_name,
            frame_prefix=old.frame_prefix,
            gather=old.gather,
        )
        vars(old).update({k: v for k, v in vars(new).items() if k not in _KEPT})


class Described(Protocol):
    """What :func:`watch_robot` reads of a run's configuration (:class:`r2d2_viz.runner.RunConfig`)."""

    @property
    def urdf(self) -> Path | None: ...
    @property
    def mappings(self) -> Mapping[str, str]: ...
    @property
    def live(self) -> bool: ...


def watch_robot(
    recording: Recording,
    source: Source | None,
    stream: RobotStream | None,
    config: Described,
    packages: PackageIndex,
    ends: ExitStack | None = None,
    poller: PollerFactory | None = None,
) -> Watching:
    """Watch the run's description (``config.urdf``, the tutorial's by default) and what it reads, for the run's
    ``stream`` driven by the generated motion ``source``, until ``ends`` closes (a reload in flight is then stopped);
    ``poller`` (tests) says when files changed."""
    if stream is None or not isinstance(source, GeneratedMotion):
        raise UsageError("--watch: only a generated motion can be reloaded (not a bag's or the graph's joints)")
    description, mappings = config.urdf or default_urdf_path(), config.mappings

    def load(read: list[Path], cancel: threading.Event | None) -> Robot:
        return load_robot(description, mappings=mappings, packages=packages, read=read, cancel=cancel)

    page = recording.page.config if recording.page is not None else None
    watching = Watching(stream, source, description, load, poller or POLLER, page, background=config.live)
    if ends is not None:
        ends.callback(watching.close)
    return watching


STARTED_NS = time.time_ns()
"""Before any robot of this process was read (this module is imported first): files whose mtime is later when the
watch begins changed after the run read them."""


def _file_watcher(files: tuple[Path, ...]) -> Poller:
    return FileWatcher(files, since_ns=STARTED_NS)


POLLER: PollerFactory = _file_watcher
"""How runs learn that files changed (tests replace it to drive reloads deterministically)."""
