"""A block of MarkerArrays (:mod:`r2d2_viz.msgs.blocks.markers`) straight to columns, one run per marker entity
(issue 46, item 3): the rows :func:`r2d2_viz.viewer.displays.log_decoded` makes for each marker — the same entities
``<topic>/<ns>/<id>``, times, components and values — built with numpy a column at a time, no Python object per
marker.

A message goes this way when every marker of it is a plain ADD: a known type, no lifetime, a frame, finite pose and
scale, and no marker of its topic has a lifetime running (their expiry is per message). Arrows, cubes, spheres,
cylinders, cube and sphere lists, points, text and one-colour line strips are columns; the other types (line
lists, meshes, triangle lists, strips coloured per point) are logged marker by marker from the block's numbers, as the
per-message path logs them. Any other message (DELETE, DELETEALL, lifetimes, an error to report) goes back to the
caller, in its turn.
"""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

import numpy as np
import numpy.typing as npt
import pyarrow as pa
import rerun as rr

from r2d2_viz.msgs.blocks.markers import MarkerBlock
from r2d2_viz.msgs.geometry import FLOAT32_MAX, frame_of
from r2d2_viz.msgs.markers import marker_op
from r2d2_viz.viewer.blocks.row_columns import RowColumns
from r2d2_viz.viewer.blocks.row_items import _BOOL, _F32, _SOLID, _U8, _VEC3, _VEC4, _texts
from r2d2_viz.viewer.displays import TEXT_RADIUS, Clock, MarkerBook, MeshLoader, _log_items, _place, marker_entity

I64 = npt.NDArray[np.int64]
ARROW, CUBE, SPHERE, CYLINDER, STRIP, CUBE_LIST, SPHERE_LIST, POINTS, TEXT = 0, 1, 2, 3, 4, 6, 7, 8, 9
_STRIP_THIN = 100  # a one-colour line strip of width 0: no radii column
_OWN = -1  # logged marker by marker
_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0], dtype=np.float32)  # xyzw


def _simple(block: MarkerBlock, frames: npt.NDArray[np.object_]) -> npt.NDArray[np.bool_]:
    """Per message: every marker a plain ADD that draws without an error (markers.marker_op's checks)."""
    pose, scale = block.pose, block.scale
    with np.errstate(all="ignore"):
        x, y, z, w = pose[:, 3], pose[:, 4], pose[:, 5], pose[:, 6]
        norm = np.sqrt(((x * x + y * y) + z * z) + w * w)
        ok = np.all(np.abs(pose[:, :3]) <= FLOAT32_MAX, axis=1) & np.all(np.abs(scale) <= FLOAT32_MAX, axis=1)
    ok &= np.isfinite(norm) & (block.action == 0) & (block.lifetime_ns <= 0)
    ok &= (block.type >= 0) & (block.type <= 11) & (frames != "")
    wrong = np.concatenate([[0], np.cumsum(~ok)])
    simple: npt.NDArray[np.bool_] = ~block.bad & (wrong[block.first[1:]] == wrong[block.first[:-1]])
    return simple


def _kinds(block: MarkerBlock) -> I64:
    """Per marker: the type when it goes as columns (a thin strip: :data:`_STRIP_THIN`), else :data:`_OWN`."""
    columns = (ARROW, CUBE, SPHERE, CYLINDER, CUBE_LIST, SPHERE_LIST, POINTS, TEXT)
    kind = np.where(np.isin(block.type, columns), block.type, _OWN).astype(np.int64)
    points, colors = np.diff(block.points_at), np.diff(block.colors_at)
    strip = (block.type == STRIP) & ~((points > 0) & (colors == points))  # one colour: the marker's
    kind[strip] = np.where(block.scale[strip, 0] / 2 > 0, STRIP, _STRIP_THIN)
    return kind


class _Numbers:
    """What every marker's row needs, for the whole block at once (RViz's conversions, as markers.py makes them)."""

    def __init__(self, block: MarkerBlock, frames: npt.NDArray[np.object_]) -> None:
        self.block, self.frames = block, frames
        self.translation = block.pose[:, :3].astype(np.float32)
        q = block.pose[:, 3:]
        x, y, z, w = q.T
        with np.errstate(all="ignore"):
            norm = np.sqrt(((x * x + y * y) + z * z) + w * w)
            unit = q / norm[:, None]
        unit[norm < 1e-12] = (0.0, 0.0, 0.0, 1.0)  # all zeros reads as identity, as RViz does
        self.xyzw = unit.astype(np.float32)
        self.scale = block.scale.astype(np.float32)
        c = np.round(np.clip(np.nan_to_num(block.color.astype(np.float64), nan=0.0), 0.0, 1.0) * 255).astype(np.uint8)
        self.color = np.ascontiguousarray(c).view(">u4").ravel().astype(np.uint32)
        c = np.round(np.clip(np.nan_to_num(block.colors.astype(np.float64), nan=0.0), 0.0, 1.0) * 255).astype(np.uint8)
        self.colors = np.concatenate([self.color, np.ascontiguousarray(c).view(">u4").ravel().astype(np.uint32)])
        """The markers' colours, then every point's (packed RGBA8)."""


def _vectors(build: Any, values: np.ndarray) -> tuple[pa.Array, I64]:
    array, _ = build([values])
    return array, np.ones(len(values), dtype=np.int64)


def _shape_columns(kind: int, sel: I64, n: _Numbers) -> list[tuple[rr.ComponentDescriptor, tuple[pa.Array, Any]]]:
    """The shape's components of markers ``sel`` (one row each), as :func:`row_items.row_of` makes them."""
    rows = len(sel)
    zeros, ones = np.zeros((rows, 3), np.float32), np.ones(rows, dtype=np.int64)
    color = (pa.array(n.color[sel], type=pa.uint32()), ones)
    if kind in (CUBE, SPHERE):
        cls = rr.Boxes3D if kind == CUBE else rr.Ellipsoids3D
        return [
            (cls.descriptor_half_sizes(), _vectors(_VEC3, n.scale[sel] / np.float32(2))),
            (cls.descriptor_centers(), _vectors(_VEC3, zeros)),
            (cls.descriptor_quaternions(), _vectors(_VEC4, np.tile(_IDENTITY, (rows, 1)))),
            (cls.descriptor_colors(), color),
            (cls.descriptor_fill_mode(), _vectors(_U8, np.full(rows, _SOLID, np.uint8))),
        ]
    if kind == CYLINDER:
        s = n.scale[sel]
        return [
            (rr.Cylinders3D.descriptor_lengths(), _vectors(_F32, s[:, 2])),
            (rr.Cylinders3D.descriptor_radii(), _vectors(_F32, (s[:, 0] + s[:, 1]) / np.float32(4))),
            (rr.Cylinders3D.descriptor_centers(), _vectors(_VEC3, zeros)),
            (rr.Cylinders3D.descriptor_quaternions(), _vectors(_VEC4, np.tile(_IDENTITY, (rows, 1)))),
            (rr.Cylinders3D.descriptor_colors(), color),
            (rr.Cylinders3D.descriptor_fill_mode(), _vectors(_U8, np.full(rows, _SOLID, np.uint8))),
        ]
    if kind == TEXT:
        return [
            (rr.Points3D.descriptor_positions(), _vectors(_VEC3, zeros)),
            (rr.Points3D.descriptor_radii(), _vectors(_F32, np.full(rows, TEXT_RADIUS, np.float32))),
            (rr.Points3D.descriptor_colors(), color),
            (rr.Points3D.descriptor_labels(), (_texts(n.block.text[sel].tolist())[0], ones)),
            (rr.Points3D.descriptor_show_labels(), _vectors(_BOOL, np.ones(rows, dtype=np.bool_))),
        ]
    if kind == ARROW:
        return _arrows(sel, n, color)
    if kind in (CUBE_LIST, SPHERE_LIST, POINTS):
        return _lists(kind, sel, n)
    return _strips(kind, sel, n, color)


def _arrows(sel: I64, n: _Numbers, color: tuple[pa.Array, I64]) -> list[tuple[rr.ComponentDescriptor, Any]]:
    b = n.block
    two = (b.points_at[sel + 1] - b.points_at[sel]) >= 2  # from the first point to the second, shaft scale.x
    start = b.points_at[sel]
    p0 = b.points[np.where(two, start, 0)].astype(np.float32) if len(b.points) else np.zeros((len(sel), 3), np.float32)
    p1 = b.points[np.where(two, start + 1, 0)].astype(np.float32) if len(b.points) else p0
    flat = np.zeros((len(sel), 3), np.float32)
    flat[:, 0] = b.scale[sel, 0]  # else along x, scale.x long, shaft scale.y
    origins = np.where(two[:, None], p0, np.float32(0))
    vectors = np.where(two[:, None], p1 - p0, flat)
    radii = np.where(two, b.scale[sel, 0] / 2, b.scale[sel, 1] / 2).astype(np.float32)
    return [
        (rr.Arrows3D.descriptor_vectors(), _vectors(_VEC3, vectors)),
        (rr.Arrows3D.descriptor_origins(), _vectors(_VEC3, origins)),
        (rr.Arrows3D.descriptor_radii(), _vectors(_F32, radii)),
        (rr.Arrows3D.descriptor_colors(), color),
    ]


def _ranges(starts: I64, counts: I64) -> I64:
    """``starts[k] + 0 … counts[k] - 1`` for every ``k``, one after the other."""
    before = np.cumsum(counts) - counts
    ranges: I64 = np.repeat(starts - before, counts) + np.arange(int(counts.sum()))
    return ranges


def _lists(kind: int, sel: I64, n: _Numbers) -> list[tuple[rr.ComponentDescriptor, Any]]:
    """Cube and sphere lists (a box or sphere a point, ``scale`` each) and points (``scale.x`` wide: the components
    of the ``rr.Points3D`` they were logged as), coloured per point when there is a colour per point (RViz's
    rule), else the marker's colour."""
    b = n.block
    counts = b.points_at[sel + 1] - b.points_at[sel]
    per_point = (counts > 0) & (b.colors_at[sel + 1] - b.colors_at[sel] == counts)
    color_lengths = np.where(per_point, counts, 1)
    starts = np.where(per_point, len(b.id) + b.colors_at[sel], sel)
    colors = (pa.array(n.colors[_ranges(starts, color_lengths)], pa.uint32()), color_lengths)
    centers = (_VEC3([b.points[_ranges(b.points_at[sel], counts)].astype(np.float32).reshape(-1, 3)])[0], counts)
    if kind == POINTS:
        return [
            (rr.Points3D.descriptor_positions(), centers),
            (rr.Points3D.descriptor_radii(), _vectors(_F32, n.scale[sel, 0] / np.float32(2))),
            (rr.Points3D.descriptor_colors(), colors),
        ]
    cls = rr.Boxes3D if kind == CUBE_LIST else rr.Ellipsoids3D
    return [
        (cls.descriptor_half_sizes(), (_VEC3([np.repeat(n.scale[sel] / np.float32(2), counts, axis=0)])[0], counts)),
        (cls.descriptor_centers(), centers),
        (cls.descriptor_quaternions(), (_VEC4([np.tile(_IDENTITY, (int(counts.sum()), 1))])[0], counts)),
        (cls.descriptor_colors(), colors),
        (cls.descriptor_fill_mode(), _vectors(_U8, np.full(len(sel), _SOLID, np.uint8))),
    ]


def _strips(kind: int, sel: I64, n: _Numbers, color: tuple[pa.Array, I64]) -> list[tuple[rr.ComponentDescriptor, Any]]:
    """One-colour line strips: a strip through the points (none below two), the marker's colour."""
    b = n.block
    counts = b.points_at[sel + 1] - b.points_at[sel]
    drawn = counts > 1
    at = _ranges(b.points_at[sel[drawn]], counts[drawn])
    points, _ = _VEC3([b.points[at].astype(np.float32).reshape(-1, 3)])
    offsets = np.zeros(int(drawn.sum()) + 1, dtype=np.int32)
    np.cumsum(counts[drawn], out=offsets[1:])
    kind_type = pa.list_(pa.field("item", points.type, nullable=False))
    lists = pa.Array.from_buffers(kind_type, len(offsets) - 1, [None, pa.py_buffer(offsets)], children=[points])
    out = [(rr.LineStrips3D.descriptor_strips(), (lists, drawn.astype(np.int64)))]
    if kind == STRIP:
        out.append((rr.LineStrips3D.descriptor_radii(), _vectors(_F32, (b.scale[sel, 0] / 2).astype(np.float32))))
    return [*out, (rr.LineStrips3D.descriptor_colors(), color)]


def _marker(b: MarkerBlock, j: int) -> Any:
    """Marker ``j`` as the attributes markers.py reads of a deserialised one."""

    def ns(**kw: Any) -> SimpleNamespace:
        return SimpleNamespace(**kw)

    def xyz(v: Any) -> SimpleNamespace:
        return ns(x=float(v[0]), y=float(v[1]), z=float(v[2]))

    p, c, stamp = b.pose[j], b.color[j], int(b.stamp_ns[j])
    rgba = ("r", "g", "b", "a")
    return ns(
        header=ns(frame_id=b.frame[j], stamp=ns(sec=stamp // 1_000_000_000, nanosec=stamp % 1_000_000_000)),
        ns=b.ns[j],
        id=int(b.id[j]),
        type=int(b.type[j]),
        action=int(b.action[j]),
        pose=ns(position=xyz(p[:3]), orientation=ns(x=float(p[3]), y=float(p[4]), z=float(p[5]), w=float(p[6]))),
        scale=xyz(b.scale[j]),
        color=ns(**{k: float(v) for k, v in zip(rgba, c, strict=True)}),
        lifetime=ns(sec=0, nanosec=0),
        frame_locked=bool(b.frame_locked[j]),
        points=[xyz(q) for q in b.points[b.points_at[j] : b.points_at[j + 1]]],
        colors=[
            ns(**{k: float(v) for k, v in zip(rgba, q, strict=True)})
            for q in b.colors[b.colors_at[j] : b.colors_at[j + 1]]
        ],
        text=b.text[j],
        mesh_resource=b.mesh_resource[j],
        mesh_use_embedded_materials=bool(b.embedded[j]),
    )


class MarkerColumns:
    """Logs a topic's :class:`MarkerBlock` s on ``rows`` (the display feed's), its state in the topic's book."""

    def __init__(self, rows: RowColumns, timeline: str, clock: Clock, load_mesh: MeshLoader | None) -> None:
        self.rows, self.timeline, self.clock, self.load_mesh = rows, timeline, clock, load_mesh

    def log(
        self,
        topic: str,
        times_ns: I64,
        block: MarkerBlock,
        book: MarkerBook,
        *,
        own: Callable[[int], None],
        count: Callable[[int], object],
    ) -> None:
        """Log the block's messages at ``times_ns`` in order: runs of plain ones as columns (``count`` called for
        each), each other one by ``own`` (the per-message path) in its turn."""
        with np.errstate(all="ignore"):  # hostile values (1e300 as float32) turn inf silently, as per message
            frames = np.array([frame_of(f) for f in block.frame], dtype=object) if len(block.frame) else block.frame
            simple, numbers, kinds = _simple(block, frames), _Numbers(block, frames), _kinds(block)
            i, total = 0, len(times_ns)
            while i < total:
                if not simple[i] or any(t is not None for t in book.live.values()):
                    own(i)
                    i += 1
                    continue
                j = i
                while j < total and simple[j]:
                    count(j)
                    j += 1
                self._run(topic, times_ns, numbers, kinds, book, (i, j))
                i = j

    def _run(self, topic: str, times_ns: I64, n: _Numbers, kinds: I64, book: MarkerBook, span: tuple[int, int]) -> None:
        b, (i, j) = n.block, span
        lo, hi = int(b.first[i]), int(b.first[j])
        self.rows.at(int(times_ns[j - 1]))
        if hi == lo:
            return
        t = np.repeat(times_ns[i:j], np.diff(b.first[i : j + 1]))
        _, codes = np.unique(b.ns[lo:hi], return_inverse=True)
        key = (codes.astype(np.int64) << 32) | (b.id[lo:hi].astype(np.int64) & 0xFFFFFFFF)
        _, inverse = np.unique(key, return_inverse=True)
        order = np.argsort(inverse, kind="stable")
        cuts = np.flatnonzero(np.diff(inverse[order])) + 1
        for members in np.split(order, cuts):
            self._entity(
                marker_entity(topic, b.ns[lo + members[0]], int(b.id[lo + members[0]])),
                members + lo,
                t[members],
                n,
                kinds,
                book,
            )
        self.rows.at(int(times_ns[j - 1]))

    def _entity(self, entity: str, sel: I64, t: I64, n: _Numbers, kinds: I64, book: MarkerBook) -> None:
        frames = n.frames
        _place(self.rows, entity, frames[sel[0]], book, (self.timeline, int(t[0]), self.clock))
        book.frames[entity] = frames[sel[-1]]
        book.live[entity] = None
        kind = kinds[sel]
        for part in np.split(np.arange(len(sel)), np.flatnonzero(np.diff(kind)) + 1):
            k, s = int(kind[part[0]]), sel[part]
            if k == _OWN:
                for row, j in zip(t[part], s, strict=True):
                    self.rows.at(int(row))
                    op = marker_op(_marker(n.block, int(j)))
                    assert op.decoded is not None
                    _log_items(self.rows, entity, op.decoded, self.load_mesh)
                continue
            ones = np.ones(len(s), dtype=np.int64)
            columns = [
                (rr.CoordinateFrame.descriptor_frame(), (_texts(frames[s].tolist())[0], ones)),
                *_shape_columns(k, s, n),
                (rr.InstancePoses3D.descriptor_translations(), _vectors(_VEC3, n.translation[s])),
                (rr.InstancePoses3D.descriptor_quaternions(), _vectors(_VEC4, n.xyzw[s])),
            ]
            self.rows.add_block(entity, tuple(d for d, _ in columns), t[part], [c for _, c in columns])
