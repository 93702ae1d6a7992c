"""Where a frame is, in another, at given times, from transforms as recorded (``/tf`` and ``/tf_static``):
tf2's lookup (latest value at or before each time; static edges hold always), vectorised over the times.
For views that frame what a bag shows. Pure numpy."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from r2d2_viz.arrays import F64, I64
from r2d2_viz.kinematics.transforms import quat_multiply, quat_to_matrix
from r2d2_viz.sources.base import TfRecords

MAX_DEPTH = 256
"""A chain longer than this is a cycle in hostile data: the lookup gives up."""


@dataclass(frozen=True)
class _Edge:
    parent: str
    times_ns: I64  # ascending; static edges: one row at the lowest time
    translation: F64
    quat_xyzw: F64


def _edges(records: Sequence[TfRecords]) -> dict[str, _Edge]:
    """child → its edge to its parent (a child recorded under several parents keeps the latest one's)."""
    rows: dict[str, list[tuple[int, str, F64, F64]]] = {}
    for r in records:
        for i, (parent, child) in enumerate(zip(r.parents, r.children, strict=True)):
            t = np.iinfo(np.int64).min if r.static else int(r.times_ns[i])
            rows.setdefault(child, []).append((t, parent, r.translation[i], r.quat_xyzw[i]))
    edges = {}
    for child, found in rows.items():
        found.sort(key=lambda row: row[0])
        parent = found[-1][1]
        kept = [row for row in found if row[1] == parent]
        edges[child] = _Edge(
            parent,
            np.array([row[0] for row in kept], dtype=np.int64),
            np.array([row[2] for row in kept], dtype=np.float64),
            np.array([row[3] for row in kept], dtype=np.float64),
        )
    return edges


def frame_positions(records: Sequence[TfRecords], fixed: str, frames: Sequence[str], times_ns: I64) -> dict[str, F64]:
    """Origins ``(N, 3)`` in ``fixed`` of each of ``frames`` that the recorded tree joins to ``fixed`` from
    above (``fixed`` an ancestor), at ``times_ns``; frames it does not join are left out."""
    edges = _edges(records)
    times = np.asarray(times_ns, dtype=np.int64)
    out: dict[str, F64] = {}
    for frame in frames:
        pose = _pose(edges, fixed, frame, times)
        if pose is not None:
            out[frame] = pose[0]
    return out


def frame_pose(records: Sequence[TfRecords], fixed: str, frame: str, times_ns: I64) -> tuple[F64, F64] | None:
    """``(translation (N, 3), quaternion xyzw (N, 4))`` of ``frame`` in ``fixed`` at ``times_ns``, or None."""
    return _pose(_edges(records), fixed, frame, np.asarray(times_ns, dtype=np.int64))


def _pose(edges: dict[str, _Edge], fixed: str, frame: str, times: I64) -> tuple[F64, F64] | None:
    n = len(times)
    t = np.zeros((n, 3))
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    at = frame
    for _ in range(MAX_DEPTH):
        if at == fixed:
            return t, q
        edge = edges.get(at)
        if edge is None:
            return None
        k = np.clip(np.searchsorted(edge.times_ns, times, side="right") - 1, 0, len(edge.times_ns) - 1)
        t_pc, q_pc = edge.translation[k], edge.quat_xyzw[k]  # parent ← child, at each time
        t = t_pc + np.einsum("nij,nj->ni", quat_to_matrix(q_pc), t)
        q = quat_multiply(q_pc, q)
        at = edge.parent
    return None


class TfLookup:
    """:func:`frame_pose` for many lookups in the same records (their index built once)."""

    def __init__(self, records: Sequence[TfRecords]) -> None:
        self._edges = _edges(records)

    def pose(self, fixed: str, frame: str, times_ns: I64) -> tuple[F64, F64] | None:
        """``(translation (N, 3), quaternion xyzw (N, 4))`` of ``frame`` in ``fixed`` at ``times_ns``, or None."""
        return _pose(self._edges, fixed, frame, np.asarray(times_ns, dtype=np.int64))
