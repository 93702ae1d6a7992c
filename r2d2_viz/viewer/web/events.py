"""The page's tool events, checked and typed: a :class:`Pick` (the points a tool was clicked at, in the view's
fixed frame, as the viewer reported them, and the view's eye when the page knows it) or a :class:`Drive` (a teleop
velocity). Anything else is refused with
:class:`~r2d2_viz.errors.ToolEventError`: the page is reachable by whoever has the URL, and what it sends may
be published to a robot. Pure: no rerun.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from r2d2_viz.errors import ToolEventError
from r2d2_viz.rviz.tools import GOAL_POSE, MEASURE, POSE_ESTIMATE, PUBLISH_POINT, TELEOP, TOOLS

CLICKS = {POSE_ESTIMATE: 2, GOAL_POSE: 2, PUBLISH_POINT: 1, MEASURE: 2}
"""How many clicks each tool takes: a position (and a second point for the heading, or the distance's end)."""
MAX_COORDINATE = 1e6
"""Metres: a picked point farther than 1000 km from the fixed frame's origin is not a click."""
MAX_SPEED = 10.0
"""m/s and rad/s: the largest teleop velocity the page may ask for."""
MAX_ENTITY = 512


Point = tuple[float, float, float]


@dataclass(frozen=True)
class Pick:
    """A tool used in the 3D view: ``points`` (x, y, z in the fixed frame), ``entity`` the last one was on, ``eye``
    the view's camera position (fixed frame) when the page knows it."""

    tool: str
    points: tuple[Point, ...]
    entity: str | None = None
    eye: Point | None = None

    def on_ground(self) -> Pick:
        """The pick as RViz's pose tools take it (``PoseTool`` → ``getViewportPointProjectionOnXYPlane``): each
        click's ray — from the eye through the point picked on whatever is drawn — met with the fixed frame's z = 0
        plane; without an eye, the points picked, straight down. ToolEventError when a ray does not meet the plane
        in front of the eye (RViz sends nothing then)."""
        if self.eye is None:
            return replace(self, points=tuple((x, y, 0.0) for x, y, _ in self.points))
        ex, ey, ez = self.eye
        grounded: list[Point] = []
        for x, y, z in self.points:
            if ez <= 0 or ez - z <= 1e-9:  # an eye under the ground, or a ray going up or along it
                raise ToolEventError(f"{self.tool}: the click's ray does not meet the ground (z = 0)")
            t = ez / (ez - z)  # E + t (P - E) has z = 0; t >= 1 when the point is above the ground
            grounded.append((ex + t * (x - ex), ey + t * (y - ey), 0.0))
        return replace(self, points=tuple(grounded))

    @property
    def yaw(self) -> float:
        """Radians, from the first point towards the second (2D Goal Pose, 2D Pose Estimate), in the x-y plane."""
        (x0, y0, _), (x1, y1, _) = self.points[0], self.points[-1]
        return math.atan2(y1 - y0, x1 - x0)

    @property
    def distance(self) -> float:
        """Metres between the first and the last point (Measure)."""
        return math.dist(self.points[0], self.points[-1])


@dataclass(frozen=True)
class Drive:
    """A teleop velocity: ``linear`` m/s forward, ``angular`` rad/s counter-clockwise (0, 0: stop)."""

    linear: float
    angular: float

    @property
    def moving(self) -> bool:
        return self.linear != 0.0 or self.angular != 0.0


def _number(value: Any, what: str, bound: float) -> float:
    finite = isinstance(value, int) or (isinstance(value, float) and math.isfinite(value))
    if isinstance(value, bool) or not finite:
        raise ToolEventError(f"{what}: expected a finite number, got {str(value)[:40]!r}")
    if abs(value) > bound:  # exact for an int of 400 digits too (which no float holds: never format it as one)
        raise ToolEventError(f"{what}: {str(value)[:20]} is out of range (at most {bound:g})")
    return float(value)


def parse_event(event: dict[str, Any]) -> Pick | Drive:
    """The page's JSON → a :class:`Pick` or a :class:`Drive`; ToolEventError for anything else."""
    tool = event.get("tool")
    if tool not in TOOLS:
        raise ToolEventError(f"unknown tool {str(tool)[:40]!r}; expected one of {', '.join(TOOLS)}")
    if tool == TELEOP:
        if set(event) - {"tool", "linear", "angular"}:
            raise ToolEventError("Teleop: expected only linear and angular")
        return Drive(
            _number(event.get("linear"), "linear", MAX_SPEED), _number(event.get("angular"), "angular", MAX_SPEED)
        )
    if set(event) - {"tool", "points", "entity", "eye"}:
        raise ToolEventError(f"{tool}: expected only points, entity and eye")
    points = event.get("points")
    if not isinstance(points, list) or len(points) != CLICKS[tool]:
        raise ToolEventError(f"{tool}: expected {CLICKS[tool]} clicked point{'s' if CLICKS[tool] > 1 else ''}")
    parsed: list[Point] = []
    for point in points:
        if not isinstance(point, list) or len(point) != 3:
            raise ToolEventError(f"{tool}: a point is [x, y, z]")
        x, y, z = (_number(v, f"{tool}: coordinate", MAX_COORDINATE) for v in point)
        parsed.append((x, y, z))
    entity = event.get("entity")
    if entity is not None and (not isinstance(entity, str) or len(entity) > MAX_ENTITY):
        raise ToolEventError(f"{tool}: entity is an entity path")
    eye = event.get("eye")
    if eye is not None and (not isinstance(eye, list) or len(eye) != 3):
        raise ToolEventError(f"{tool}: the eye is [x, y, z]")
    ex, ey, ez = (_number(v, f"{tool}: eye", MAX_COORDINATE) for v in eye) if eye is not None else (0.0, 0.0, 0.0)
    return Pick(tool, tuple(parsed), entity, None if eye is None else (ex, ey, ez))
