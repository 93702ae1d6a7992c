"""The Python API for Rerun users: log *your* robot and *your* joint trajectories into *your* recording.

    import numpy as np, rerun as rr, r2d2_viz

    rr.init("my_app", spawn=True)
    robot = r2d2_viz.load_robot("arm.urdf")            # a URDF or xacro file; or r2d2_viz.parse_urdf(text)
    logger = r2d2_viz.RobotLogger(robot)                # the current recording, or recording=rec
    logger.log_static()                                 # meshes, fixed transforms, TF axes and arrows, plot styles
    t = np.linspace(0, 10, 1001)
    logger.log_joint_positions(t, np.sin(t)[:, None] * np.ones(len(logger.joints)))
    logger.finish()                                     # limit lines up to the last sample

A script can take picks from the viewer as its input, with r2d2-viz's page (RViz's tools in the web viewer)::

    page = r2d2_viz.serve_tools(fixed_frame="map")      # prints nothing; page.url is what to open
    r2d2_viz.on_pick(lambda pick: print(pick.tool, pick.points))   # every 2D Goal Pose, Publish Point, …

Same pinned kinematics and the same entities as the ``r2d2-viz`` command line (``/tf``, ``/tf_static/…``,
``/robot/visual/…``, ``/joints/…``); :func:`r2d2_viz.generate_blueprint` gives the RViz-like layout.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from r2d2_viz.errors import UsageError, listed
from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import Robot
from r2d2_viz.robot.xacro_load import load_robot
from r2d2_viz.ros_out.tools_out import PICK_CALLBACKS, ToolOutput, attach_tools, detach_tools
from r2d2_viz.runner import BATCH_CHUNK_SAMPLES
from r2d2_viz.sources.base import ArraySource, Clock, FrameTrack, Source
from r2d2_viz.sources.motion import ODOM
from r2d2_viz.viewer.entities import TIMELINE
from r2d2_viz.viewer.notices import Warn, to_stderr
from r2d2_viz.viewer.sinks import Recording, SinkConfig, close_recording, current_recording, serve_recording
from r2d2_viz.viewer.stream import RobotStream
from r2d2_viz.viewer.web.events import Pick

if TYPE_CHECKING:
    from rerun import RecordingStream  # annotations only: the viewer stage talks to Rerun


class RobotLogger:
    """Logs one robot into a Rerun recording.

    ``moving_root``: every :meth:`log_joint_positions` call also gives the root's pose in ``fixed_frame``
    (``root_translation``, ``root_quat_xyzw``); otherwise the root sits at the fixed frame's origin.
    ``timestamps``: times are seconds since the Unix epoch (a timestamp timeline) instead of seconds since
    the start (a duration timeline). ``robot`` given as a path may be a URDF or a xacro file (its ``NAME:=VALUE``
    arguments in ``mappings``; ``package://`` and ``$(find)`` resolved as the command line does)."""

    def __init__(
        self,
        robot: Robot | str | Path,
        *,
        recording: RecordingStream | None = None,
        fixed_frame: str = ODOM,
        moving_root: bool = False,
        timestamps: bool = False,
        timeline: str = TIMELINE,
        warn: Warn = to_stderr,
        mappings: Mapping[str, str] | None = None,
    ) -> None:
        self.robot = robot if isinstance(robot, Robot) else load_robot(robot, mappings=mappings)
        rec = current_recording(recording)
        self.tree = compile_tree(self.robot)
        self._frames = ((fixed_frame, self.robot.root),) if moving_root else ()
        self._clock: Clock = "timestamp" if timestamps else "duration"
        self.stream = RobotStream(
            rec,
            self.tree,
            frames=self._frames,
            clock=self._clock,
            fixed_frame=fixed_frame,
            timeline=timeline,
            warn=warn,
        )

    @property
    def joints(self) -> tuple[str, ...]:
        """The robot's actuated joints: the default columns of :meth:`log_joint_positions`."""
        return self.tree.actuated

    def log_static(self) -> None:
        """Everything that does not move; once, before any sample."""
        self.stream.log_static()

    def log_joint_positions(
        self,
        times: npt.ArrayLike,
        positions: npt.ArrayLike,
        *,
        joints: Sequence[str] | None = None,
        root_translation: npt.ArrayLike | None = None,
        root_quat_xyzw: npt.ArrayLike | None = None,
    ) -> None:
        """Log ``positions`` ``(T, J)`` of ``joints`` (default :attr:`joints`) at ``times`` ``(T,)`` in seconds
        (floats, or numpy ``timedelta64`` / ``datetime64``). Joints left out, or NaN, keep their last value.
        Mimic joints follow their masters; values outside the URDF limits are shown unclamped and reported."""
        times_ns = _nanoseconds(times)
        names = tuple(self.joints if joints is None else joints)
        q = np.asarray(positions, dtype=np.float64).reshape(len(times_ns), -1)
        if q.shape[1] != len(names):
            raise UsageError(f"positions have {q.shape[1]} columns for {len(names)} joints ({listed(names)})")
        unknown = [name for name in names if name not in self.joints]
        if unknown:
            raise UsageError(
                f"not actuated joints of {self.robot.name!r}: {listed(unknown)}; "
                f"expected some of its {len(self.joints)}: {listed(self.joints)}"
            )
        tracks: list[FrameTrack] = []
        for parent, child in self._frames:
            if root_translation is None or root_quat_xyzw is None:
                raise UsageError("moving_root=True: give root_translation (T, 3) and root_quat_xyzw (T, 4)")
            translation = np.asarray(root_translation, dtype=np.float64).reshape(-1, 3)
            quat = np.asarray(root_quat_xyzw, dtype=np.float64).reshape(-1, 4)
            tracks.append(FrameTrack(parent, child, translation, quat))
        self.log_source(ArraySource(times_ns, names, q, tracks=tracks, clock=self._clock))

    def log_source(self, source: Source) -> None:
        """Log every sample of a finite ``source`` (e.g. ``r2d2_viz.make_motion(robot, "sweep", n_samples=300)``).
        Its frame tracks must be the ones this logger was made for."""
        if tuple(source.frames) != self._frames:
            raise UsageError(f"the source moves frames {source.frames}, this logger was made for {self._frames}")
        for chunk in source.chunks(BATCH_CHUNK_SAMPLES):
            self.stream.send(self.stream.prepare(chunk))

    def finish(self) -> None:
        """Pending plot values and the limit lines up to the last sample."""
        self.stream.finish()


def _nanoseconds(times: npt.ArrayLike) -> npt.NDArray[np.int64]:
    array = np.asarray(times)
    if np.issubdtype(array.dtype, np.datetime64) or np.issubdtype(array.dtype, np.timedelta64):
        unit = "datetime64[ns]" if np.issubdtype(array.dtype, np.datetime64) else "timedelta64[ns]"
        return array.astype(unit).astype(np.int64).reshape(-1)
    seconds = array.astype(np.float64).reshape(-1)
    if not np.isfinite(seconds).all():
        raise UsageError("times must be finite numbers of seconds")
    return np.rint(seconds * 1e9).astype(np.int64)


def on_pick(callback: Callable[[Pick], None]) -> Callable[[], None]:
    """Call ``callback`` (from the page's server thread) with every use of a tool in r2d2-viz's page — the
    ``r2d2-viz --serve`` page or :func:`serve_tools`'s: a :class:`~r2d2_viz.viewer.web.events.Pick` with the tool's
    name and its clicked points in the fixed frame. Returns a function that unsubscribes."""
    PICK_CALLBACKS.append(callback)
    return lambda: PICK_CALLBACKS.remove(callback) if callback in PICK_CALLBACKS else None


class ToolsPage:
    """r2d2-viz's page for a script's recording (:func:`serve_tools`); :attr:`url` to open, :meth:`close` to stop."""

    def __init__(self, recording: Recording, tools: ToolOutput | None) -> None:
        self.recording, self.tools = recording, tools
        page = recording.page
        self.url = page.url() if page is not None else ""

    def close(self) -> None:
        detach_tools(self.recording, self.tools)
        close_recording(self.recording)


def serve_tools(
    recording: RecordingStream | None = None,
    *,
    fixed_frame: str = ODOM,
    bind: str = "127.0.0.1",
    port: int = 9876,
    web_port: int = 9090,
    say: Callable[[str], None] = lambda line: None,
) -> ToolsPage:
    """Stream ``recording`` (default: the current one) to r2d2-viz's page — Rerun's web viewer with RViz's tools,
    on ``bind`` behind a per-run token — instead of its other sinks. The tools pick, draw and call
    :func:`on_pick`'s callbacks (and ``say`` with each line); nothing is published. ``port`` is unused (the page
    carries the recording: no gRPC port is opened), kept so that calls which pass it still work."""
    served = serve_recording(
        current_recording(recording), SinkConfig(serve=True, bind=bind, port=port, web_port=web_port)
    )
    return ToolsPage(served, attach_tools(served, fixed_frame, say=say))
