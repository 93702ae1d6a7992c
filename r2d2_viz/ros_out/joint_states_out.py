"""The sliders on the live graph (``--ros --motion sliders``): ``/joint_states`` as ``joint_state_publisher``
publishes it — ``sensor_msgs/msg/JointState`` with the joints' names and positions (no velocities or efforts), at
10 Hz — through the app's DDS participant, the one RViz's tools publish with (:mod:`r2d2_viz.ros_out.tools_out`).
The app's own subscription then shows the robot as any node on the graph sees it.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

import numpy as np

from r2d2_viz.errors import UsageError
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.sources.motion import SlidersMotion
from r2d2_viz.sources.sliders import SliderBoard

if TYPE_CHECKING:
    from r2d2_viz.robot.model import Robot

JOINT_STATES = "/joint_states"
JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"
PERIOD_S = 0.1
"""joint_state_publisher's default rate: 10 Hz."""


class Publisher(Protocol):
    def publish(self, topic: str, ros_type: str, data: bytes) -> None: ...


def joint_state_cdr(names: tuple[str, ...], positions: list[float], stamp_ns: int, frame: str = "") -> bytes:
    """One JointState message, CDR with its header (rosbags' typestore serialises it)."""
    store = typestore()
    types = store.types
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000),
        frame_id=frame,
    )
    message = types[JOINT_STATE_TYPE](
        header=header,
        name=list(names),
        position=np.asarray(positions, dtype=np.float64),
        velocity=np.zeros(0, dtype=np.float64),
        effort=np.zeros(0, dtype=np.float64),
    )
    return bytes(store.serialize_cdr(message, JOINT_STATE_TYPE))


class JointStatesOut:
    """Publishes ``board``'s values on ``/joint_states`` every ``period`` seconds in a thread, until :meth:`close`;
    ``stamp`` (ns since the epoch) and ``wait`` are injectable for tests."""

    def __init__(
        self,
        board: SliderBoard,
        publisher: Publisher,
        *,
        period: float = PERIOD_S,
        stamp: Callable[[], int] = time.time_ns,
    ) -> None:
        self.board, self.publisher, self.period, self.stamp = board, publisher, period, stamp
        self.names = tuple(s.name for s in board.sliders)
        self.sent = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def publish_once(self) -> None:
        data = joint_state_cdr(self.names, [float(v) for v in self.board.values()], self.stamp())
        self.publisher.publish(JOINT_STATES, JOINT_STATE_TYPE, data)
        self.sent += 1

    def start(self) -> JointStatesOut:
        def beat() -> None:
            while not self._stop.is_set():
                try:
                    self.publish_once()
                except Exception as exc:  # the graph went away: say it once, stop publishing
                    print(f"warning: {JOINT_STATES}: not published any more: {exc}", flush=True)
                    return
                self._stop.wait(self.period)

        self._thread = threading.Thread(target=beat, name="r2d2-viz-joint-states", daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2)


def live_sliders(motion: str | None, robot: Robot | None) -> SlidersMotion | None:
    """``--ros --motion sliders``: the sliders of the robot the run shows (``--urdf``, or the graph's
    ``/robot_description``); None for any other run."""
    if motion != "sliders":
        return None
    if robot is None:
        raise UsageError("--ros --motion sliders: no robot to make sliders for: give --urdf (the graph published "
                         "no /robot_description)")  # fmt: skip
    return SlidersMotion(robot)
