"""A view that fits any robot: where its links go over its motion, and how far the camera must stand.

The tutorial keeps r2d2.rviz's exact view. Any other robot gets the same orbit angles with the focal point at
the centre of the space its links sweep over a stretch of its motion and the distance that shows all of it,
and TF axes scaled to its size (RViz's TF "Marker Scale"). Pure numpy; no rerun import.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from r2d2_viz.arrays import F64
from r2d2_viz.kinematics.tree import KinematicTree, link_positions, moving_values, transforms_from_values
from r2d2_viz.robot.model import Box, Cylinder, MeshFile, Sphere
from r2d2_viz.sources.base import FrameTrack

FOV_Y = math.radians(45.0)
"""The 3D view's vertical field of view (Rerun's default eye)."""
MARGIN = 1.15
"""Room around the robot."""
AXIS_LENGTH = 0.1
"""RViz draws TF axes 0.1 m long at marker scale 1."""
MANY_FRAMES = 40
FIT_LIMIT = 1e9
"""Points farther than this (m, on any axis) from the origin are left out of a fit, like NaN: no robot's scene is
that big, and the camera placed from such an extent would be infinite as the viewer's float32 (a map lying about
its size, a 1e300 transform)."""
"""Above this many TF frames the arrows are hidden and the axes are half as long: they would cover the robot."""


@dataclass(frozen=True)
class ViewFit:
    center: tuple[float, float, float]
    """Centre of the box the robot's links sweep (in the fixed frame)."""
    radius: float
    """Half the diagonal of that box, plus the largest shape's size."""
    frames: int
    """TF frames drawn (links plus the fixed frame)."""
    robot_radius: float | None = None
    """The robot's own size, when the view also frames where it went and what it saw (TF axes follow the
    robot, not the scene)."""

    def distance(self) -> float:
        """Orbit distance at which a sphere of :attr:`radius` fills the view's height (with a margin)."""
        return MARGIN * self.radius / math.sin(FOV_Y / 2)

    def marker_scale(self) -> float:
        """RViz's TF marker scale for this robot: 1 for a 2 m robot, in proportion to its size, halved when
        there are many frames."""
        size = self.radius if self.robot_radius is None else self.robot_radius
        scale = min(max(size, 0.05), 20.0)
        return scale / 2 if self.frames > MANY_FRAMES else scale

    def axis_length(self) -> float:
        return AXIS_LENGTH * self.marker_scale()

    @property
    def show_arrows(self) -> bool:
        return self.frames <= MANY_FRAMES


def fit_view(tree: KinematicTree, q: F64, *, root: FrameTrack | None = None) -> ViewFit:
    """The fit for joint positions ``q`` ``(T, A)`` (a stretch of the robot's motion) and, if the source moves
    the root, its pose ``root`` at those samples."""
    q = np.asarray(q, dtype=np.float64)
    q = q.reshape(len(q) if q.ndim == 2 else 1, len(tree.actuated))
    translation, quat = transforms_from_values(tree, moving_values(tree, q))
    root_pose = None
    if root is not None:
        root_pose = (root.translation, root.quat_xyzw)
    at = link_positions(tree, translation, quat, range(len(tree.links)), root_pose=root_pose)
    points = _usable(np.concatenate([p for p in at.values()]))
    if len(points) == 0:
        points = np.zeros((1, 3))
    lo, hi = points.min(axis=0), points.max(axis=0)
    center = (lo + hi) / 2
    size = max((_shape_size(shape.geometry) for link in tree.robot.links for shape in link.visuals), default=0.0)
    radius = min(max(float(np.linalg.norm(hi - lo)) / 2 + size, 0.05), FIT_LIMIT)
    cx, cy, cz = (float(v) for v in center)
    return ViewFit((cx, cy, cz), radius, len(tree.links) + 1)


def fit_scene(groups: list[F64], *, robot_radius: float, frames: int) -> ViewFit:
    """A view of point ``groups`` (where a robot went; what each display message draws) with a robot of
    ``robot_radius`` among them. Of a group of more than 100 points, 2 % at either end of each axis are left out,
    so a few far readings of one scan do not shrink the scene; a small group (a marker) counts whole."""
    lows, highs = [], []
    for group in groups:
        points = _usable(np.asarray(group, dtype=np.float64).reshape(-1, 3))
        if len(points) == 0:
            continue
        if len(points) > 100:
            lows.append(np.percentile(points, 2, axis=0))
            highs.append(np.percentile(points, 98, axis=0))
        else:
            lows.append(points.min(axis=0))
            highs.append(points.max(axis=0))
    lo = np.min(lows, axis=0) if lows else np.zeros(3)
    hi = np.max(highs, axis=0) if highs else np.zeros(3)
    cx, cy, cz = (float(v) for v in (lo + hi) / 2)
    radius = min(max(float(np.linalg.norm(hi - lo)) / 2 + robot_radius, 0.05), FIT_LIMIT)
    return ViewFit((cx, cy, cz), radius, frames, robot_radius=robot_radius or None)


def _usable(points: F64) -> F64:
    """The points a fit may use: finite and within :data:`FIT_LIMIT` of the origin on every axis."""
    with np.errstate(invalid="ignore"):
        return points[(np.abs(points) <= FIT_LIMIT).all(axis=1)]


def _shape_size(geometry: object) -> float:
    """Distance from a shape's origin to its farthest point (meshes: their scale, as their size is not known
    before they are read)."""
    if isinstance(geometry, Box):
        return float(np.linalg.norm(geometry.size)) / 2
    if isinstance(geometry, Cylinder):
        return math.hypot(geometry.radius, geometry.length / 2)
    if isinstance(geometry, Sphere):
        return geometry.radius
    if isinstance(geometry, MeshFile):
        return 0.0
    return 0.0
