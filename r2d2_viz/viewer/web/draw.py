"""What the tools draw in the viewer, in the fixed frame (``CoordinateFrame``): the pickable ground, and each
message sent — an arrow for a pose, a sphere for a point, a line and its length for a measure — under
``/tools/<topic>`` (static: the last one of each stays, as RViz shows the last goal)."""

from __future__ import annotations

import math

import numpy as np
import rerun as rr

from r2d2_viz.msgs.geometry import rotate
from r2d2_viz.msgs.shapes import GridMap, Pose
from r2d2_viz.viewer.entities import path

GROUND = "/tools/ground"
GROUND_HALF_SIZE = 50.0
"""Metres around the fixed frame's origin when no map in the fixed frame gives the ground its extent."""
FLOAT32_MAX = float(np.finfo(np.float32).max)
Extent = tuple[float, float, float, float]
"""(x0, y0, x1, y1) in the fixed frame."""
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


def map_extent(origin: Pose, resolution: float, width: int, height: int) -> Extent | None:
    """The xy box of a ``width`` x ``height`` map of ``resolution`` m cells whose cell (0, 0) corner is at
    ``origin`` (nav_msgs/MapMetaData; a rotated origin turns the map about that corner), clamped to finite float32;
    None when it has no finite box (a NaN or infinite origin)."""
    w, h = float(width) * float(resolution), float(height) * float(resolution)
    corners = np.array([[0.0, 0.0, 0.0], [w, 0.0, 0.0], [w, h, 0.0], [0.0, h, 0.0]])
    with np.errstate(all="ignore"):  # hostile sizes: judged below, not warned about
        placed = rotate(origin.xyzw, corners) + np.asarray(origin.translation, dtype=np.float64)
    if not np.isfinite(placed).all():
        return None
    placed = np.clip(placed, -FLOAT32_MAX, FLOAT32_MAX)
    (x0, y0), (x1, y1) = placed[:, :2].min(axis=0), placed[:, :2].max(axis=0)
    return float(x0), float(y0), float(x1), float(y1)


class ToolDrawing:
    """Draws into ``rec`` in ``fixed_frame``; the ground in the view's ``background`` colour."""

    def __init__(
        self, rec: rr.RecordingStream, fixed_frame: str, background: tuple[int, int, int] = (48, 48, 48)
    ) -> None:
        self.rec, self.fixed_frame, self.background = rec, fixed_frame, background
        self.extent: Extent | None = None
        """The maps' extent the ground covers (None: no map yet, 50 m around the origin)."""

    def cover(self, frame: str, grid: GridMap) -> bool:
        """A map arrived in ``frame``: the ground grows to cover it too when it is in the fixed frame (maps in
        other frames are not transformed: the ground stays as it is); whether the ground was drawn again."""
        if frame != self.fixed_frame:
            return False
        height, width = grid.rgba.shape[:2]
        extent = map_extent(grid.T_frame_item, grid.resolution, width, height)
        if extent is None:
            return False
        if self.extent is not None:
            (a0, b0, a1, b1), (c0, d0, c1, d1) = self.extent, extent
            extent = min(a0, c0), min(b0, d0), max(a1, c1), max(b1, d1)
            if extent == self.extent:
                return False
        self.extent = extent
        self.ground(extent)
        return True

    def ground(self, extent: Extent | None = None) -> None:
        """A z = 0 rectangle over ``extent`` (None: 50 m around the fixed frame's origin)."""
        h = GROUND_HALF_SIZE
        x0, y0, x1, y1 = extent if extent is not None else (-h, -h, h, h)
        corners = np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]], dtype=np.float32)
        self.rec.log(
            GROUND,
            rr.CoordinateFrame(self.fixed_frame),
            rr.Mesh3D(
                vertex_positions=corners,
                triangle_indices=[[0, 1, 2], [0, 2, 3]],
                albedo_factor=(*self.background, GROUND_ALPHA),
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
