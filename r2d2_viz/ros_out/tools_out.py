"""What the page's tools send, as RViz sends it: each :class:`~r2d2_viz.viewer.web.events.Pick` or
:class:`~r2d2_viz.viewer.web.events.Drive` becomes its ROS 2 message (CDR from rosbags' typestore), published on
the live graph when there is one (``--ros``), drawn in the viewer and said in one line — without a graph (a bag
replay) the tools still draw and print, a way to read coordinates off a recording.

Teleop publishes each velocity the page sends (10 Hz while a key is held) and zero on release; if the page goes
quiet while moving (closed, crashed, network gone), :meth:`ToolOutput.check_teleop` sends the zero itself after
:data:`TELEOP_TIMEOUT_S`.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Protocol

from r2d2_viz.errors import R2d2VizError, shown
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.ros_out.joint_states_out import JointStatesOut
from r2d2_viz.rviz.tools import GOAL_POSE, MEASURE, MESSAGE_TYPES, POSE_ESTIMATE, PUBLISH_POINT, TELEOP, tool_topics
from r2d2_viz.sources.motion import SlidersMotion
from r2d2_viz.sources.sliders import SLIDERS, SliderBoard
from r2d2_viz.viewer.layout.plan import ViewPlan
from r2d2_viz.viewer.sinks import Recording
from r2d2_viz.viewer.web.draw import ToolDrawing
from r2d2_viz.viewer.web.events import Drive, Pick, parse_event

if TYPE_CHECKING:  # a type: the page's server (http.server) is imported only by a run that serves a page
    from r2d2_viz.viewer.web.server import EventHandler

INITIAL_POSE_COVARIANCE = {0: 0.25, 7: 0.25, 35: 0.06853891945200942}
"""RViz's 2D Pose Estimate: x and y variance 0.25 m², yaw 0.0685 rad² ((π/12)²), row-major 6x6 indices."""
TELEOP_TIMEOUT_S = 0.5
"""A moving teleop with no word from the page for this long is stopped (a zero Twist)."""
PICK_CALLBACKS: list[Callable[[Pick], None]] = []
"""Called with every pick of every page (:func:`r2d2_viz.api.on_pick`)."""


def say_line(line: str) -> None:
    """The tools' lines go to stdout, one each (a script can read the clicked coordinates off it); a frame name
    from a bag shows its control characters (``\\x1b``), never sends them to the terminal."""
    print(shown(line), file=sys.stdout, flush=True)


class Publisher(Protocol):
    """What of :class:`~r2d2_viz.sources.live.dds.LiveGraph` the tools use."""

    def publish(self, topic: str, ros_type: str, data: bytes) -> None: ...


def _header(frame: str, stamp_ns: int) -> Any:
    t = typestore().types
    stamp = t["builtin_interfaces/msg/Time"](sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)
    return t["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)


def _pose(position: tuple[float, float, float], yaw: float) -> Any:
    t = typestore().types
    # a rotation by yaw about z, quaternion xyzw
    q = t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))
    return t["geometry_msgs/msg/Pose"](
        position=t["geometry_msgs/msg/Point"](x=position[0], y=position[1], z=position[2]), orientation=q
    )


def tool_message(pick: Pick, frame: str, stamp_ns: int) -> Any:
    """The message RViz's tool sends for ``pick`` (2D Goal Pose and Pose Estimate at z = 0, yaw from the first
    click towards the second)."""
    t = typestore().types
    header = _header(frame, stamp_ns)
    x, y, z = pick.points[0]
    if pick.tool == PUBLISH_POINT:
        return t["geometry_msgs/msg/PointStamped"](header=header, point=t["geometry_msgs/msg/Point"](x=x, y=y, z=z))
    pose = _pose((x, y, 0.0), pick.yaw)
    if pick.tool == GOAL_POSE:
        return t["geometry_msgs/msg/PoseStamped"](header=header, pose=pose)
    if pick.tool == POSE_ESTIMATE:
        import numpy as np

        covariance = np.zeros(36, dtype=np.float64)
        for index, value in INITIAL_POSE_COVARIANCE.items():
            covariance[index] = value
        with_covariance = t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=covariance)
        return t["geometry_msgs/msg/PoseWithCovarianceStamped"](header=header, pose=with_covariance)
    raise R2d2VizError(f"{pick.tool} sends no message")


def twist_message(drive: Drive) -> Any:
    t = typestore().types
    v3 = t["geometry_msgs/msg/Vector3"]
    return t["geometry_msgs/msg/Twist"](
        linear=v3(x=drive.linear, y=0.0, z=0.0), angular=v3(x=0.0, y=0.0, z=drive.angular)
    )


def _xyz(p: tuple[float, float, float]) -> str:
    return f"({p[0]:.2f}, {p[1]:.2f}, {p[2]:.2f})"


class ToolOutput:
    """Handles the page's events for a run in ``fixed_frame`` (``topics``: each tool's, over RViz's defaults):
    publishes through ``publisher`` (None: no graph), draws with ``drawing`` (None: nothing drawn), says each line
    with ``say``."""

    def __init__(
        self,
        fixed_frame: str,
        *,
        topics: Mapping[str, str] | None = None,
        publisher: Publisher | None = None,
        drawing: ToolDrawing | None = None,
        say: Callable[[str], None] = print,
        clock: Callable[[], float] = time.monotonic,
        stamp: Callable[[], int] = time.time_ns,
    ) -> None:
        self.fixed_frame = fixed_frame
        self.topics = tool_topics(overrides=topics)
        self.publisher, self.drawing, self.say, self.clock, self.stamp = publisher, drawing, say, clock, stamp
        self._lock = threading.Lock()
        self._drive = Drive(0.0, 0.0)
        self._last_drive = 0.0
        self._stop = threading.Event()
        self._watchdog: threading.Thread | None = None
        self.closers: list[Callable[[], None]] = []
        """Called by :meth:`close` (the sliders' ``/joint_states``)."""

    def handle(self, event: dict[str, Any]) -> str:
        """One event from the page (checked: :func:`~r2d2_viz.viewer.web.events.parse_event`) → the line said."""
        parsed = parse_event(event)
        if isinstance(parsed, Drive):
            return self.drive(parsed)
        return self.pick(parsed)

    def pick(self, pick: Pick) -> str:
        frame = self.fixed_frame
        if pick.tool in (GOAL_POSE, POSE_ESTIMATE):
            pick = pick.on_ground()  # RViz's pose tools: the ground under the pointer, whatever is drawn there
        if pick.tool == MEASURE:
            line = f"measured: {pick.distance:.3f} m in {frame} from {_xyz(pick.points[0])} to {_xyz(pick.points[-1])}"
            if self.drawing is not None:
                self.drawing.measure(pick.points[0], pick.points[-1], pick.distance)
        else:
            topic = self.topics[pick.tool]
            x, y, _ = pick.points[0]
            if pick.tool == PUBLISH_POINT:
                line = f"clicked: {frame} {_xyz(pick.points[0])}"
                if self.drawing is not None:
                    self.drawing.point(topic, pick.points[0])
            else:
                what = "goal" if pick.tool == GOAL_POSE else "initial pose"
                line = f"{what}: {frame} ({x:.2f}, {y:.2f}) yaw {math.degrees(pick.yaw):.1f}°"
                if self.drawing is not None:
                    self.drawing.pose(topic, (x, y, 0.0), pick.yaw, estimate=pick.tool == POSE_ESTIMATE)
            line += self._publish(pick.tool, tool_message(pick, frame, self.stamp()))
        for callback in list(PICK_CALLBACKS):
            callback(pick)
        self.say(line)
        return line

    def drive(self, drive: Drive) -> str:
        with self._lock:
            changed = drive != self._drive
            self._drive, self._last_drive = drive, self.clock()
        where = self._publish(TELEOP, twist_message(drive))
        if drive.moving:
            self._start_watchdog()
        line = (
            f"teleop: {drive.linear:.2f} m/s, {drive.angular:.2f} rad/s{where}"
            if drive.moving
            else f"teleop: stopped{where}"
        )
        if changed:
            self.say(line)
        return line

    def check_teleop(self) -> bool:
        """Stop a teleop the page stopped talking about (True when a zero was sent)."""
        with self._lock:
            late = self._drive.moving and self.clock() - self._last_drive > TELEOP_TIMEOUT_S
        if late:
            self.drive(Drive(0.0, 0.0))
        return late

    def close(self) -> None:
        """A robot driven from the page stops when the app does."""
        self._stop.set()
        if self._drive.moving:
            self.drive(Drive(0.0, 0.0))
        for close in self.closers:
            close()

    def _publish(self, tool: str, message: Any) -> str:
        if self.publisher is None:
            return ""
        topic, ros_type = self.topics[tool], MESSAGE_TYPES[tool]
        self.publisher.publish(topic, ros_type, bytes(typestore().serialize_cdr(message, ros_type)))
        return f" → {topic}"

    def _start_watchdog(self) -> None:
        if self._watchdog is not None:
            return

        def watch() -> None:
            while not self._stop.wait(0.1):
                self.check_teleop()

        self._watchdog = threading.Thread(target=watch, name="r2d2-viz-teleop", daemon=True)
        self._watchdog.start()


def attach_tools(
    recording: Recording,
    fixed_frame: str,
    *,
    config_topics: Mapping[str, str] | None = None,
    overrides: Mapping[str, str] | None = None,
    publisher: Publisher | None = None,
    say: Callable[[str], None] = say_line,
    background: tuple[int, int, int] = (48, 48, 48),
    sliders: SliderBoard | None = None,
) -> ToolOutput | None:
    """Connect ``--serve``'s page (if the recording has one) to a :class:`ToolOutput`: the ground drawn, the page
    told the fixed frame and topics, its events handled; ``background``: the 3D view's (the ground's colour);
    ``sliders``: the joint sliders of ``--motion sliders`` (their events to them). None when there is no page."""
    page = recording.page
    if page is None:
        return None
    drawing = ToolDrawing(recording.rec, fixed_frame, background)
    drawing.ground()
    output = ToolOutput(
        fixed_frame, topics=tool_topics(config_topics, overrides), publisher=publisher, drawing=drawing, say=say
    )
    page.config.update(fixed_frame=fixed_frame, topics=output.topics, publishing=publisher is not None)
    page.set_handler(output.handle if sliders is None else with_sliders(sliders, output.handle))
    if sliders is not None:
        page.config.update(joints=sliders.describe())
        if publisher is not None:  # --ros: the sliders on /joint_states at 10 Hz, as joint_state_publisher
            output.closers.append(JointStatesOut(sliders, publisher).start().close)
    return output


def with_sliders(board: SliderBoard, tools: EventHandler) -> EventHandler:
    """The page's events: the sliders' (``"tool": "Joints"``) to ``board``, RViz's tools' to ``tools``."""

    def handle(event: dict[str, Any]) -> str:
        return board.handle(event) if event.get("tool") == SLIDERS else tools(event)

    return handle


def attach_view_tools(
    recording: Recording,
    view: ViewPlan,
    overrides: Mapping[str, str],
    *,
    publisher: Publisher | None = None,
    source: object = None,
) -> ToolOutput | None:
    """:func:`attach_tools` for a run laid out as ``view``: its fixed frame, its config's tool topics under
    ``overrides`` (``--tool-topic``), its background; ``source``: what moves the robot (sliders: on the page)."""
    spec = view.spec
    frame = view.layout.fixed_frame or spec.fixed_frame
    topics = dict(spec.tool_topics)
    sliders = source.board if isinstance(source, SlidersMotion) else None  # the run's source: sliders?
    return attach_tools(recording, frame, config_topics=topics, overrides=overrides, publisher=publisher,
                        background=spec.background, sliders=sliders)  # fmt: skip


def detach_tools(recording: Recording, output: ToolOutput | None) -> None:
    """The page takes no more events; a teleop still moving is stopped."""
    if recording.page is not None:
        recording.page.set_handler(None)
    if output is not None:
        output.close()
