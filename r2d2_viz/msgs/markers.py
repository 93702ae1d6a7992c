"""visualization_msgs Marker and MarkerArray: each marker one ``MarkerOp`` keyed by ``(ns, id)``.

Sizes follow RViz's marker conventions: ``scale`` is the full size of cubes, spheres and cylinders, the line /
point width of lines and points, the shaft diameter / head diameter / head length of a two-point arrow and the
length / width / height of a pose arrow; text is ``scale.z`` tall; triangle lists are scaled by ``scale``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from r2d2_viz.msgs.geometry import colors8, header_of, one_color, points3, pose_of, rgba8, xyz
from r2d2_viz.msgs.shapes import (
    F32,
    U8,
    Arrows,
    Boxes,
    Cylinders,
    Decoded,
    DecodeOptions,
    Ellipsoids,
    LineStrips,
    MarkerOp,
    MeshResource,
    Points,
    Pose,
    Shape,
    Text,
    TriangleMesh,
)
from r2d2_viz.msgs.typestore import MsgError, deserialize

ADD, MODIFY, DELETE, DELETEALL = 0, 0, 2, 3


def _colors(m: Any, n: int) -> U8:
    """Per-point colours when there is one per point (RViz's rule), else the marker colour."""
    if n and len(m.colors) == n:
        return colors8(m.colors)
    return one_color(rgba8(m.color))


def _identity(n: int) -> F32:
    q = np.zeros((n, 4), dtype=np.float32)
    q[:, 3] = 1.0
    return q


def _arrow(m: Any, pose: Pose) -> Shape:
    sx, sy, _ = xyz(m.scale)
    color = one_color(rgba8(m.color))
    if len(m.points) >= 2:
        p = points3(m.points[:2])
        return Arrows(p[:1], p[1:2] - p[:1], color, sx / 2, pose)
    vector = np.array([[sx, 0.0, 0.0]], dtype=np.float32)
    return Arrows(np.zeros((1, 3), np.float32), vector, color, sy / 2, pose)


def _solid(m: Any, pose: Pose) -> Shape:
    size = np.array([xyz(m.scale)], dtype=np.float32)
    half = (size / 2).astype(np.float32)
    centers, color, q = np.zeros((1, 3), np.float32), one_color(rgba8(m.color)), _identity(1)
    if m.type == 1:
        return Boxes(centers, half, q, color, pose)
    if m.type == 2:
        return Ellipsoids(centers, half, q, color, pose)
    radius = np.array([(size[0, 0] + size[0, 1]) / 4], dtype=np.float32)  # an elliptic base reads as round
    return Cylinders(centers, size[:, 2].copy(), radius, q, color, pose)


def _lines(m: Any, pose: Pose) -> Shape:
    p = points3(m.points)
    colors = _colors(m, p.shape[0])
    width = xyz(m.scale)[0]
    if m.type == 5:  # LINE_LIST: pairs
        n = p.shape[0] // 2 * 2
        segments = p[:n].reshape(-1, 2, 3)
        return LineStrips(tuple(segments), colors[0:n:2] if colors.shape[0] > 1 else colors, width / 2, pose)
    if colors.shape[0] > 1 and p.shape[0] > 1:  # a strip with per-point colours: one segment per colour
        segments = np.stack([p[:-1], p[1:]], axis=1)
        return LineStrips(tuple(segments), colors[:-1], width / 2, pose)
    return LineStrips((p,) if p.shape[0] > 1 else (), colors[:1], width / 2, pose)


def _lists(m: Any, pose: Pose) -> Shape:
    p = points3(m.points)
    colors = _colors(m, p.shape[0])
    size = np.array(xyz(m.scale), dtype=np.float32)
    if m.type == 8:  # POINTS: scale.x is the width
        return Points(p, colors, float(size[0]) / 2, pose)
    half = np.tile(size / 2, (p.shape[0], 1)).astype(np.float32)
    cls = Boxes if m.type == 6 else Ellipsoids
    return cls(p, half, _identity(p.shape[0]), colors, pose)


def _text(m: Any, pose: Pose) -> Shape:
    return Text(str(m.text), (0.0, 0.0, 0.0), xyz(m.scale)[2], rgba8(m.color), pose)


def _mesh(m: Any, pose: Pose) -> Shape:
    color = None if m.mesh_use_embedded_materials else rgba8(m.color)
    return MeshResource(str(m.mesh_resource), xyz(m.scale), color, pose)


def _triangles(m: Any, pose: Pose) -> Shape:
    p = points3(m.points)
    n = p.shape[0] // 3 * 3
    vertices = (p[:n] * np.array(xyz(m.scale), dtype=np.float32)).astype(np.float32)
    indices = np.arange(n, dtype=np.uint32).reshape(-1, 3)
    if n and len(m.colors) == n // 3:  # one colour per triangle
        colors = np.repeat(colors8(m.colors), 3, axis=0)
    else:
        colors = _colors(m, p.shape[0])[: max(n, 1)]
    return TriangleMesh(vertices, indices, colors, pose)


SHAPES: dict[int, Callable[[Any, Pose], Shape]] = {
    0: _arrow,
    1: _solid,
    2: _solid,
    3: _solid,
    4: _lines,
    5: _lines,
    6: _lists,
    7: _lists,
    8: _lists,
    9: _text,
    10: _mesh,
    11: _triangles,
}


def marker_op(m: Any) -> MarkerOp:
    """One deserialised Marker as a ``MarkerOp``."""
    ns, key = str(m.ns), int(m.id)
    if m.action == DELETE:
        return MarkerOp("delete", ns, key)
    if m.action == DELETEALL:
        return MarkerOp("deleteall", ns, key)
    if m.action != ADD:
        raise MsgError(f"marker {ns!r}/{key}: unknown action {m.action}")
    shape = SHAPES.get(int(m.type))
    if shape is None:
        raise MsgError(f"marker {ns!r}/{key}: unknown type {m.type}")
    frame, stamp = header_of(m)
    lifetime = max(0, int(m.lifetime.sec) * 1_000_000_000 + int(m.lifetime.nanosec))
    decoded = Decoded(frame, stamp, (shape(m, pose_of(m.pose)),))
    return MarkerOp("add", ns, key, decoded, lifetime, bool(m.frame_locked))


def decode_marker(data: bytes | memoryview, options: DecodeOptions) -> list[MarkerOp]:
    """A Marker as one ``MarkerOp``."""
    return [marker_op(deserialize(data, "visualization_msgs/msg/Marker"))]


def decode_marker_array(data: bytes | memoryview, options: DecodeOptions) -> list[MarkerOp]:
    """A MarkerArray as its markers' ``MarkerOp``s, in order."""
    return [marker_op(m) for m in deserialize(data, "visualization_msgs/msg/MarkerArray").markers]
