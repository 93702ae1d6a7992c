"""Where a decoded message's drawings lie in its frame: a few points that span each drawing, for a view that
frames what a bag holds (a map's corners, a scan's points, a marker's centre). Pure numpy."""

from __future__ import annotations

import numpy as np

from r2d2_viz.arrays import F64
from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.geometry import rotate
from r2d2_viz.msgs.shapes import Decoded, MarkerOp

MAX_POINTS = 2000
"""At most this many points a drawing (a cloud is thinned evenly)."""


def _local(item: shapes.Shape) -> F64 | None:
    """Points spanning ``item`` in its own coordinates (before ``T_frame_item``)."""
    if isinstance(item, shapes.Points):
        return np.asarray(item.positions, dtype=np.float64)
    if isinstance(item, shapes.LineStrips):
        return np.concatenate(list(item.strips)).astype(np.float64) if len(item.strips) else None
    if isinstance(item, shapes.Arrows):
        origins = np.asarray(item.origins, dtype=np.float64)
        return np.concatenate([origins, origins + np.asarray(item.vectors, dtype=np.float64)])
    if isinstance(item, (shapes.Boxes, shapes.Ellipsoids, shapes.Cylinders)):
        return np.asarray(item.centers, dtype=np.float64)
    if isinstance(item, shapes.TriangleMesh):
        return np.asarray(item.vertices, dtype=np.float64)
    if isinstance(item, shapes.Text):
        return np.array([item.position], dtype=np.float64)
    if isinstance(item, shapes.MeshResource):
        return np.zeros((1, 3))
    if isinstance(item, shapes.GridMap):
        h, w = item.rgba.shape[:2]
        r = item.resolution
        return np.array([[0, 0, 0], [w * r, 0, 0], [w * r, h * r, 0], [0, h * r, 0]], dtype=np.float64)
    return None  # images, camera models: no place in 3D of their own


def extent_points(decoded: Decoded | list[MarkerOp], *, maps: bool = True) -> F64:
    """Points ``(K, 3)`` in the message frame spanning what ``decoded`` draws (finite ones only); without the
    corners of occupancy maps when not ``maps`` (a map is the background: it can be far bigger than the scene)."""
    parts = [decoded] if isinstance(decoded, Decoded) else [op.decoded for op in decoded if op.decoded is not None]
    out = []
    for part in parts:
        for item in part.items:
            if not maps and isinstance(item, shapes.GridMap):
                continue
            local = _local(item)
            if local is None or len(local) == 0:
                continue
            local = local[:: max(1, len(local) // MAX_POINTS)]
            pose = getattr(item, "T_frame_item", shapes.IDENTITY)
            out.append(rotate(pose.xyzw, local) + np.asarray(pose.translation, dtype=np.float64))
    points = np.concatenate(out) if out else np.zeros((0, 3))
    return points[np.isfinite(points).all(axis=1)]
