"""The commonest display items as rows of plain numbers (issue 46, item 3): building Rerun's archetypes for each
message (``rr.Arrows3D(…)``, ``rr.Scalars(…)``: their converters) cost more than the rest of a display's message.

:func:`row_of` gives, for an arrow set, boxes, ellipsoids, cylinders, line strips or a label in a named frame, and
for a plotted number, a log line or a fix, the components :func:`r2d2_viz.viewer.displays.archetypes` and
:func:`~r2d2_viz.viewer.blocks.plain_log.log_plain` would log — the same descriptors, and values that become the same
Arrow arrays — as (descriptor, how its column is built, this row's value); :class:`Builder` s turn a run's values
into one Arrow array each, a numpy concatenation per column. Anything else (meshes, maps, images, states, pinholes,
items in no frame) goes through the archetypes, row by row.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.msgs import shapes
from r2d2_viz.viewer.displays import TEXT_RADIUS, packed

Builder = Callable[[list[Any]], tuple[pa.Array, list[int] | np.ndarray]]
"""A run's values of one column → (its instances as one Arrow array, how many each row has)."""
Row = list[tuple[rr.ComponentDescriptor, Builder, Any]]


def _vectors(size: int, dtype: type[np.floating[Any]] = np.float32) -> Builder:
    """Rows of ``(k, size)`` numbers → Rerun's fixed-size lists (Vec3D, Quaternion, DVec2D …)."""
    item = pa.float32() if dtype is np.float32 else pa.float64()
    kind = pa.list_(pa.field("item", item, nullable=False), size)

    def build(values: list[Any]) -> tuple[pa.Array, list[int] | np.ndarray]:
        block, lengths = _even(values, dtype, size)
        flat = pa.array(block.reshape(-1), type=item)
        return pa.FixedSizeListArray.from_arrays(flat, type=kind), lengths

    return build


def _numbers(dtype: type[np.generic], kind: pa.DataType) -> Builder:
    """Rows of numbers (one, or an array each) → one Arrow array of ``kind``."""

    def build(values: list[Any]) -> tuple[pa.Array, list[int] | np.ndarray]:
        block, lengths = _even(values, dtype, 1)
        return pa.array(block.reshape(-1), type=kind), lengths

    return build


def _even(values: list[Any], dtype: type[np.generic], size: int) -> tuple[np.ndarray, list[int] | np.ndarray]:
    """Rows of ``size``-number instances as one ``(n, size)`` block, and each row's count: in one conversion when
    every row has as many (a marker's pose, a colour, a number), else row by row."""
    try:
        block = np.array(values, dtype=dtype)
    except ValueError:  # rows of different lengths
        block = None
    if block is not None and block.ndim >= 1 and (size == 1 or (block.ndim >= 2 and block.shape[-1] == size)):
        each = int(np.prod(block.shape[1:])) // size
        return block.reshape(-1, size), np.full(len(values), each, dtype=np.int64)
    rows = [np.asarray(v, dtype=dtype).reshape(-1, size) for v in values]
    return np.concatenate(rows), [len(r) for r in rows]


def _texts(values: list[Any]) -> tuple[pa.Array, list[int] | np.ndarray]:
    return pa.array(values, type=pa.utf8()), np.ones(len(values), dtype=np.int64)


def _strips(values: list[Any]) -> tuple[pa.Array, list[int] | np.ndarray]:
    """Rows of strips (a tuple of ``(m, 3)`` each) → LineStrip3D's list of points per strip."""
    strips = [np.asarray(s, dtype=np.float32).reshape(-1, 3) for row in values for s in row]
    points, counts = _VEC3(strips or [np.zeros((0, 3), np.float32)])
    if not strips:
        counts = []
    offsets = np.zeros(len(counts) + 1, dtype=np.int32)
    np.cumsum(counts, out=offsets[1:])
    kind = pa.list_(pa.field("item", points.type, nullable=False))
    lists = pa.Array.from_buffers(kind, len(counts), [None, pa.py_buffer(offsets)], children=[points])
    return lists, [len(row) for row in values]


_VEC3, _VEC4, _DVEC2 = _vectors(3), _vectors(4), _vectors(2, np.float64)
_F32, _F64 = _numbers(np.float32, pa.float32()), _numbers(np.float64, pa.float64())
_U32, _U8, _BOOL = _numbers(np.uint32, pa.uint32()), _numbers(np.uint8, pa.uint8()), _numbers(np.bool_, pa.bool_())
_SOLID = 3
"""``rr.components.FillMode.Solid`` as Rerun stores it (``fill_mode="solid"``: what every solid shape logs)."""


def _pose(pose: shapes.Pose) -> Row:
    """``InstancePoses3D``: the item's pose in its frame (translation, ``xyzw``)."""
    return [
        (rr.InstancePoses3D.descriptor_translations(), _VEC3, pose.translation),
        (rr.InstancePoses3D.descriptor_quaternions(), _VEC4, pose.xyzw),
    ]


def row_of(item: shapes.Shape, frame: str) -> Row | None:
    """The row that logging ``item`` (drawn in ``frame``; a plain item in none) makes, or None: logged as
    archetypes."""
    if isinstance(item, shapes.Series):
        return [(rr.Scalars.descriptor_scalars(), _F64, item.values)]
    if isinstance(item, shapes.LogLine):
        text: Row = [(rr.TextLog.descriptor_text(), _texts, item.text)]
        return [*text, (rr.TextLog.descriptor_level(), _texts, item.level)] if item.level else text
    if isinstance(item, shapes.GeoPoint):
        return [
            (rr.GeoPoints.descriptor_positions(), _DVEC2, (item.latitude, item.longitude)),
            (rr.GeoPoints.descriptor_radii(), _F32, -6.0),  # rr.Radius.ui_points(6.0): negative, in UI points
        ]
    if not frame or (shaped := _shaped(item)) is None:
        return None
    return [(rr.CoordinateFrame.descriptor_frame(), _texts, frame), *shaped, *_pose(item.T_frame_item)]  # type: ignore[union-attr]


def _shaped(item: shapes.Shape) -> Row | None:
    if isinstance(item, shapes.Boxes) and (item.labels or item.edges):  # detections: as archetypes (labels, edges)
        return None
    if isinstance(item, shapes.Arrows):
        return [
            (rr.Arrows3D.descriptor_vectors(), _VEC3, item.vectors),
            (rr.Arrows3D.descriptor_origins(), _VEC3, item.origins),
            (rr.Arrows3D.descriptor_radii(), _F32, item.radius),
            (rr.Arrows3D.descriptor_colors(), _U32, packed(item.colors)),
        ]
    if isinstance(item, shapes.Boxes | shapes.Ellipsoids):
        cls = rr.Boxes3D if isinstance(item, shapes.Boxes) else rr.Ellipsoids3D
        return [
            (cls.descriptor_half_sizes(), _VEC3, item.half_sizes),
            (cls.descriptor_centers(), _VEC3, item.centers),
            (cls.descriptor_quaternions(), _VEC4, item.xyzw),
            (cls.descriptor_colors(), _U32, packed(item.colors)),
            (cls.descriptor_fill_mode(), _U8, _SOLID),
        ]
    if isinstance(item, shapes.Cylinders):
        return [
            (rr.Cylinders3D.descriptor_lengths(), _F32, item.lengths),
            (rr.Cylinders3D.descriptor_radii(), _F32, item.radii),
            (rr.Cylinders3D.descriptor_centers(), _VEC3, item.centers),
            (rr.Cylinders3D.descriptor_quaternions(), _VEC4, item.xyzw),
            (rr.Cylinders3D.descriptor_colors(), _U32, packed(item.colors)),
            (rr.Cylinders3D.descriptor_fill_mode(), _U8, _SOLID),
        ]
    if isinstance(item, shapes.LineStrips):
        strips: Row = [(rr.LineStrips3D.descriptor_strips(), _strips, item.strips)]
        if item.radius > 0:
            strips.append((rr.LineStrips3D.descriptor_radii(), _F32, item.radius))
        return [*strips, (rr.LineStrips3D.descriptor_colors(), _U32, packed(item.colors))]
    if isinstance(item, shapes.Text):
        return [
            (rr.Points3D.descriptor_positions(), _VEC3, item.position),
            (rr.Points3D.descriptor_radii(), _F32, TEXT_RADIUS),
            (rr.Points3D.descriptor_colors(), _U32, packed(np.asarray([item.color], dtype=np.uint8))),
            (rr.Points3D.descriptor_labels(), _texts, item.text),
            (rr.Points3D.descriptor_show_labels(), _BOOL, True),
        ]
    return None
