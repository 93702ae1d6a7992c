"""What the tools draw in the viewer, in the fixed frame (``CoordinateFrame``): the pickable ground, and each
message sent — an arrow for a pose, a sphere for a point, a line and its length for a measure — under
``/tools/<topic>`` (static: the last one of each stays, as RViz shows the last goal)."""

from __future__ import annotations

import math

import numpy as np
import rerun as rr

from r2d2_viz.viewer.entities import path

GROUND = "/tools/ground"
GROUND_HALF_SIZE = 50.0
"""Metres around the fixed frame's origin (or around the map, when its extent is known)."""
GROUND_ALPHA = 8
"""The view's background colour, nearly transparent: invisible, but a logged entity, so the viewer reports a click
on it with its position (a grey one tinted the view's background by 4 levels of 255)."""
ARROW_LENGTH = 1.0
POINT_RADIUS = 0.08
COLORS = {
    "pose": (25, 255, 0, 255),
    "estimate": (0, 200, 255, 255),
    "point": (255, 90, 40, 255),
    "measure": (128, 128, 0, 255),
}
"""RViz's colours: the goal arrow's green, Measure's line (128, 128, 0)."""


class ToolDrawing:
    """Draws into ``rec`` in ``fixed_frame``."""

    def __init__(self, rec: rr.RecordingStream, fixed_frame: str) -> None:
        self.rec, self.fixed_frame = rec, fixed_frame

    def ground(
        self, extent: tuple[float, float, float, float] | None = None, background: tuple[int, int, int] = (48, 48, 48)
    ) -> None:
        """A z = 0 square: ``extent`` (x0, y0, x1, y1) grown to at least 50 m around the origin, in the view's
        ``background`` colour."""
        x0, y0, x1, y1 = extent or (0.0, 0.0, 0.0, 0.0)
        h = GROUND_HALF_SIZE
        x0, y0, x1, y1 = min(x0, -h), min(y0, -h), max(x1, h), max(y1, h)
        corners = np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]], dtype=np.float32)
        self.rec.log(
            GROUND,
            rr.CoordinateFrame(self.fixed_frame),
            rr.Mesh3D(
                vertex_positions=corners,
                triangle_indices=[[0, 1, 2], [0, 2, 3]],
                albedo_factor=(*background, GROUND_ALPHA),
            ),
            static=True,
        )

    def pose(self, topic: str, position: tuple[float, float, float], yaw: float, *, estimate: bool = False) -> None:
        vector = [ARROW_LENGTH * math.cos(yaw), ARROW_LENGTH * math.sin(yaw), 0.0]
        self.rec.log(
            path("tools", *topic.strip("/").split("/")),
            rr.CoordinateFrame(self.fixed_frame),
            rr.Arrows3D(origins=[position], vectors=[vector], colors=[COLORS["estimate" if estimate else "pose"]]),
            static=True,
        )

    def point(self, topic: str, position: tuple[float, float, float]) -> None:
        self.rec.log(
            path("tools", *topic.strip("/").split("/")),
            rr.CoordinateFrame(self.fixed_frame),
            rr.Ellipsoids3D(
                centers=[position], half_sizes=[[POINT_RADIUS] * 3], colors=[COLORS["point"]], fill_mode="solid"
            ),
            static=True,
        )

    def measure(self, start: tuple[float, float, float], end: tuple[float, float, float], distance: float) -> None:
        self.rec.log(
            "/tools/measure",
            rr.CoordinateFrame(self.fixed_frame),
            rr.LineStrips3D([[start, end]], colors=[COLORS["measure"]], labels=[f"{distance:.3f} m"]),
            static=True,
        )
