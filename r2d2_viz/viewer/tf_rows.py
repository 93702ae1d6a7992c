"""Per-sample transforms: the ``/tf`` entity, one ``Transform3D`` row per moving joint and per frame track
of the source (such as ``odom → axis``) at every sample, each row naming its parent and child frames.

The TF arrows that move — prismatic joints, and a root moved by the source — ride along in the first row of
each sample, drawn in the fixed frame (``/tf``'s ``CoordinateFrame``), so a sample is one chunk.
Arrows of other frame tracks (say ``map → odom``) are not drawn.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import numpy.typing as npt
import pyarrow as pa
import rerun as rr

from r2d2_viz.arrays import F64
from r2d2_viz.kinematics.tree import (
    PRISMATIC,
    KinematicTree,
    link_positions,
    transforms_from_values,
    write_transforms,
)
from r2d2_viz.sources.base import FrameTrack
from r2d2_viz.viewer.columns import (
    Encoded,
    encoded,
    f32,
    first_of_every,
    float32_array,
    list_column,
    packed_rgba,
    tiled,
)
from r2d2_viz.viewer.scene import ARROW_COLOR


class TfRows:
    """The layout of ``/tf`` rows for one robot and one source's frame tracks."""

    def __init__(self, tree: KinematicTree, *, tracks: tuple[tuple[str, str], ...], fixed_frame: str) -> None:
        robot = tree.robot
        self.tree = tree
        moving = [robot.joint(name) for name in tree.moving]
        self.parents = [*(j.parent for j in moving), *(p for p, _ in tracks)]
        self.children = [*(j.child for j in moving), *(c for _, c in tracks)]
        self.root_track = next((k for k, edge in enumerate(tracks) if edge == (fixed_frame, robot.root)), None)
        """Which track moves the root in the fixed frame (its arrow is drawn; its pose places the others)."""
        arrow_rows = [m for m in range(len(moving)) if tree.moving_kind[m] == PRISMATIC]
        if self.root_track is not None:
            arrow_rows.append(len(moving) + self.root_track)
        index = {name: i for i, name in enumerate(tree.links)}  # the fixed frame is no link: -1
        self._arrow_ends = [(index[self.children[r]], index.get(self.parents[r], -1)) for r in arrow_rows]
        self._arrow_links = sorted({i for pair in self._arrow_ends for i in pair if i >= 0})
        self.fixed_frame = fixed_frame
        self._names: tuple[pa.StringArray, pa.StringArray] | None = None
        """The parent and child frame columns of the last chunk's length, reused (chunks are mostly one size)."""

    @property
    def rows(self) -> int:
        return len(self.children)

    def log_static(self, rec: rr.RecordingStream, entity: str) -> None:
        """The moving arrows' frame, once (their colour rides with their vectors: colours logged up front would
        be half an archetype in a run whose joint states never come — an error badge on the 3D view)."""
        if self._arrow_ends:
            rec.log(entity, rr.CoordinateFrame(self.fixed_frame), static=True)

    def encode(self, values: F64, tracks: tuple[FrameTrack, ...]) -> Encoded:
        """Columns of ``rows`` rows per sample for the moving joints' ``values`` ``(n, M)`` and the tracks: what
        ``rr.Transform3D.columns`` builds (the float32 values Rerun would cast to, a one-value list per row), built
        from buffers — Rerun's builder cost about as much as the kinematics on a 100 Hz hour-long bag."""
        n, m = len(values), len(self.tree.moving)
        t32 = np.empty((n, self.rows, 3), dtype=np.float32)
        q32 = np.empty((n, self.rows, 4), dtype=np.float32)  # xyzw
        arrows: Encoded = []
        with np.errstate(over="ignore"):  # beyond float32: ±inf, silently (see f32)
            if self._arrow_ends:  # the arrows need the float64 transforms
                translation, quat = transforms_from_values(self.tree, values)  # (n, M, 3), (n, M, 4)
                arrows = self._arrow_columns(translation, quat, tracks)
                t32[:, :m], q32[:, :m] = translation, quat
            else:
                write_transforms(self.tree, values, t32, q32)
            for k, track in enumerate(tracks, start=m):
                t32[:, k], q32[:, k] = track.translation, track.quat_xyzw
        if self._names is None or len(self._names[0]) != n * self.rows:
            self._names = (tiled(self.parents, n), tiled(self.children, n))
        columns = transform_columns(t32, q32, *self._names)
        return [*columns, *((d, first_of_every(a, self.rows)) for d, a in arrows)]

    def _arrow_columns(self, translation: F64, quat: F64, tracks: tuple[FrameTrack, ...]) -> Encoded:
        """The arrows that move, one row per sample: from each moving child's origin to its parent's, in the
        fixed frame."""
        n = len(translation)
        root = None if self.root_track is None else tracks[self.root_track]
        root_pose = None if root is None else (root.translation, root.quat_xyzw)
        at = link_positions(self.tree, translation, quat, self._arrow_links, root_pose=root_pose)
        origin = np.zeros((n, 3))
        child = np.stack([at[c] for c, _ in self._arrow_ends], axis=1)  # (n, k, 3)
        parent = np.stack([at[p] if p >= 0 else origin for _, p in self._arrow_ends], axis=1)
        k = len(self._arrow_ends)
        return arrow_columns(f32(child), f32(parent - child), per_row=k, color=ARROW_COLOR)


def transform_columns(
    translation: npt.NDArray[np.float32], quat: npt.NDArray[np.float32], parents: pa.Array, children: pa.Array
) -> Encoded:
    """One ``Transform3D`` row per transform — ``translation`` ``(..., 3)``, ``quat`` ``(..., 4)`` xyzw, float32,
    the frame names one string a row — as ``rr.Transform3D.columns`` builds them, from buffers."""
    layout = _transform_layout()
    arrays = {
        "translation": _vectors(translation, layout["translation"][1]),
        "quaternion": _vectors(quat, layout["quaternion"][1]),
        "parent_frame": parents,
        "child_frame": children,
    }
    return [(d, list_column(list_type, arrays[name])) for name, (d, list_type) in layout.items()]


def arrow_columns(
    origins: npt.NDArray[np.float32],
    vectors: npt.NDArray[np.float32],
    *,
    per_row: int = 1,
    color: tuple[int, int, int] | None = None,
) -> Encoded:
    """Arrows ``(n·per_row, 3)`` (or ``(n, per_row, 3)``), ``per_row`` a row, with one ``color`` for all or none:
    what ``rr.Arrows3D.columns(...).partition(np.full(n, per_row))`` builds, from buffers."""
    layout = _arrow_layout()
    arrays = {"origins": _vectors(origins, layout["origins"][1]), "vectors": _vectors(vectors, layout["vectors"][1])}
    if color is not None:
        arrays["colors"] = packed_rgba(color, origins.size // 3)
    return [(d, list_column(t, arrays[name], step=per_row)) for name, (d, t) in layout.items() if name in arrays]


@cache
def _transform_layout() -> dict[str, tuple[rr.ComponentDescriptor, pa.DataType]]:
    """Rerun's descriptor and Arrow list type of each ``Transform3D`` column :meth:`TfRows.encode` builds, taken
    from Rerun's own builder on one row."""
    columns = rr.Transform3D.columns(
        translation=np.zeros((1, 3), dtype=np.float32),
        quaternion=np.array([[0.0, 0.0, 0.0, 1.0]], dtype=np.float32),
        parent_frame=["parent"],
        child_frame=["child"],
    )
    return {d.component.split(":")[-1]: (d, a.type) for d, a in encoded(columns)}


@cache
def _arrow_layout() -> dict[str, tuple[rr.ComponentDescriptor, pa.DataType]]:
    """Rerun's descriptor and Arrow list type of each ``Arrows3D`` column :meth:`TfRows._arrow_columns` builds
    (origins, vectors, colors), taken from Rerun's own builder on one row."""
    columns = rr.Arrows3D.columns(
        origins=np.zeros((1, 3), dtype=np.float32),
        vectors=np.ones((1, 3), dtype=np.float32),
        colors=np.array([ARROW_COLOR], dtype=np.uint8),
    )
    return {d.component.split(":")[-1]: (d, a.type) for d, a in encoded(columns)}


def _vectors(values: npt.NDArray[np.float32], list_type: pa.DataType) -> pa.Array:
    """Rows of ``values`` ``(..., d)`` as Rerun's fixed-size lists of ``d`` floats (the list type's items)."""
    return pa.FixedSizeListArray.from_arrays(float32_array(values), type=list_type.value_type)
