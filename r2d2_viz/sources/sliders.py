"""``--motion sliders``: ``joint_state_publisher_gui`` without ROS — a slider per actuated joint in the page.

Each slider spans its joint's limits (continuous joints, and limits that are not finite, ±π; prismatic joints in
metres) and starts at joint_state_publisher's "zero": 0 when the range holds it, else the middle of the range.
"Centre" puts every slider back there, "randomise" anywhere in its range, uniformly (both as
joint_state_publisher_gui's buttons). Mimic joints have no slider: the kinematics moves them after their leader,
as robot_state_publisher does.

The page sends ``{"tool": "Joints", "joint": NAME, "position": VALUE}``, ``{"tool": "Joints", "positions":
{NAME: VALUE, …}}`` (its centre and randomise buttons) or ``{"tool": "Joints", "action": "centre" |
"randomise"}`` through the same event path as RViz's tools; anything else is refused with one line
(:class:`~r2d2_viz.errors.ToolEventError`). The motion (:class:`r2d2_viz.sources.motion.SlidersMotion`) yields
one sample per chunk, each with the sliders' values when it is taken, so a live run shows a move within one
sample. Pure numpy; no rerun import.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from r2d2_viz.arrays import F64
from r2d2_viz.errors import ToolEventError

if TYPE_CHECKING:
    from r2d2_viz.robot.model import Joint, Robot

SLIDERS = "Joints"
"""The page's name for slider events (beside RViz's tools)."""
ACTIONS = ("centre", "randomise")
MAX_NAME = 256
MAX_JOINTS = 1000


@dataclass(frozen=True)
class Slider:
    name: str
    type: str
    lower: float
    upper: float
    zero: float
    """joint_state_publisher's starting value: 0 if ``lower ≤ 0 ≤ upper``, else the middle."""


def slider(joint: Joint) -> Slider:
    limit = joint.limit
    lower, upper = (limit.lower, limit.upper) if limit is not None else (-math.pi, math.pi)
    if joint.type == "continuous" or not (math.isfinite(lower) and math.isfinite(upper)) or upper < lower:
        lower, upper = -math.pi, math.pi
    zero = 0.0 if lower <= 0.0 <= upper else (lower + upper) / 2
    return Slider(joint.name, joint.type, lower, upper, zero)


class SliderBoard:
    """The sliders' values, shared between the page's events (server threads) and the motion (the run)."""

    def __init__(self, robot: Robot, *, seed: int | None = None) -> None:
        self.sliders = tuple(slider(j) for j in robot.actuated_joints)
        self._index = {s.name: i for i, s in enumerate(self.sliders)}
        self._values = np.array([s.zero for s in self.sliders], dtype=np.float64)
        self._lock = threading.Lock()
        self._rng = np.random.default_rng(seed)

    def values(self) -> F64:
        with self._lock:
            return self._values.copy()

    def describe(self) -> list[dict[str, Any]]:
        """What the page needs to draw the sliders (JSON)."""
        values = self.values()
        return [
            {"name": s.name, "type": s.type, "lower": s.lower, "upper": s.upper, "zero": s.zero, "value": float(v)}
            for s, v in zip(self.sliders, values, strict=True)
        ]

    def set(self, name: str, position: float) -> str:
        i = self._check(name, position)
        with self._lock:
            self._values[i] = position
        return f"{name} = {position:g}"

    def centre(self) -> str:
        with self._lock:
            self._values[:] = [s.zero for s in self.sliders]
        return "Joints: centred"

    def randomise(self) -> str:
        lower = np.array([s.lower for s in self.sliders])
        upper = np.array([s.upper for s in self.sliders])
        with self._lock:
            self._values[:] = self._rng.uniform(lower, upper) if len(lower) else lower
        return "Joints: randomised"

    def handle(self, event: dict[str, Any]) -> str:
        """One slider event from the page → the line the page shows; ToolEventError for anything else."""
        if event.get("tool") != SLIDERS:
            raise ToolEventError(f"not a slider event: {str(event.get('tool'))[:40]!r}")
        if "action" in event:
            if set(event) != {"tool", "action"} or event["action"] not in ACTIONS:
                raise ToolEventError(f"Joints: expected an action, one of {', '.join(ACTIONS)}")
            return self.centre() if event["action"] == "centre" else self.randomise()
        if "positions" in event:  # several at once (the page's centre and randomise): all checked, then all set
            positions = event["positions"]
            if set(event) != {"tool", "positions"} or not isinstance(positions, dict) or len(positions) > MAX_JOINTS:
                raise ToolEventError("Joints: expected positions, an object of joint names and positions")
            checked = {str(k): self._position(str(k), v) for k, v in positions.items()}
            for joint, value in checked.items():
                self._check(joint, value)
            with self._lock:
                for joint, value in checked.items():
                    self._values[self._index[joint]] = value
            return f"Joints: {len(checked)} set"
        name, position = event.get("joint"), event.get("position")
        if set(event) != {"tool", "joint", "position"} or not isinstance(name, str) or len(name) > MAX_NAME:
            raise ToolEventError("Joints: expected a joint's name and its position")
        return self.set(name, self._position(name, position))

    @staticmethod
    def _position(name: str, value: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ToolEventError(f"Joints: {name[:60]}: expected a finite position, got {str(value)[:40]!r}")
        try:
            position = float(value)  # an int of 400 digits (JSON has no limit) holds no float: out of range
        except OverflowError:
            raise ToolEventError(f"Joints: {name[:60]}: {str(value)[:20]}… is out of range") from None
        if not math.isfinite(position):
            raise ToolEventError(f"Joints: {name[:60]}: expected a finite position, got {str(value)[:40]!r}")
        return position

    def _check(self, name: str, position: float) -> int:
        i = self._index.get(name)
        if i is None:
            raise ToolEventError(f"Joints: no slider {name[:60]!r} (the robot's actuated joints have one each)")
        s = self.sliders[i]
        if not s.lower <= position <= s.upper:
            raise ToolEventError(f"Joints: {name} = {position:g} is outside [{s.lower:g}, {s.upper:g}]")
        return i
