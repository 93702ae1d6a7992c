"""The frames a robot's description adds to the TF tree, as robot_state_publisher publishes them (and as the replay
draws them): every fixed joint a static edge (``/tf_static``, once), every moving joint a dynamic edge at each
joint-states sample that gives its value (a mimic joint with the joint it follows), and a generated motion's frame
tracks (the tutorial's ``odom → axis``, state_publisher.py's broadcast) at every sample. Edges that the recorded TF
already holds are left to it (``skip``): what was published is what the recording says. Pure; no rerun import."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import I64
from r2d2_viz.kinematics.tree import KinematicTree
from r2d2_viz.sources.base import SampleChunk, Source, TfRecords
from r2d2_viz.sources.system.tf_tree import TfRows, TfTree, analyse

Rows = tuple[npt.NDArray[np.object_], npt.NDArray[np.object_], I64]
"""Parents, children (str arrays) and times (ns) of transform rows."""


@dataclass(frozen=True)
class RobotFrames:
    """The robots of a run (``trees``: one per joint-states source, in the order of their chunks), the extra frame
    edges every sample carries (``tracks``) and the edges left to the recorded TF (``skip``)."""

    trees: tuple[KinematicTree, ...]
    tracks: tuple[tuple[str, str], ...] = ()
    skip: frozenset[tuple[str, str]] = frozenset()

    def static_edges(self) -> list[tuple[str, str]]:
        """Every fixed joint's ``(parent, child)``, as robot_state_publisher latches them on ``/tf_static``."""
        out = []
        for tree in self.trees:
            for name in tree.static:
                joint = tree.robot.joint(name)
                if (joint.parent, joint.child) not in self.skip:
                    out.append((joint.parent, joint.child))
        return sorted(set(out))

    def moving_edges(self) -> set[tuple[str, str]]:
        """The edges :meth:`rows` may give: every moving joint's and every track's (but those skipped)."""
        joints = {edge for tree in self.trees for _, edge in self._moving(tree)}
        return joints | (set(self.tracks) - self.skip)

    def static_records(self, time_ns: int) -> TfRecords:
        """:meth:`static_edges` as static rows at ``time_ns`` (identity transforms: for the TF tree, not drawn)."""
        edges = self.static_edges()
        return _records(np.full(len(edges), time_ns, np.int64), [p for p, _ in edges], [c for _, c in edges], True)

    def rows(self, chunks: Sequence[SampleChunk | None]) -> Rows:
        """Parents, children and times of the dynamic rows of ``chunks`` (``chunks[i]``: the samples of
        ``trees[i]``), in time order: a moving joint's edge at each sample that gives the joint it follows, and
        every track at every sample of the first chunk."""
        parents: list[npt.NDArray[np.object_]] = []
        children: list[npt.NDArray[np.object_]] = []
        times: list[I64] = []
        for k, (tree, chunk) in enumerate(zip(self.trees, chunks, strict=False)):
            if chunk is None or not len(chunk):
                continue
            edges = self._moving(tree)
            column = {name: i for i, name in enumerate(chunk.joints)}
            for m, (parent, child) in edges:
                source = column.get(tree.actuated[int(tree.moving_source[m])])
                if source is None:
                    continue
                given = np.flatnonzero(~np.isnan(chunk.positions[:, source]))
                times.append(chunk.times_ns[given])
                parents.append(_repeated(parent, len(given)))
                children.append(_repeated(child, len(given)))
            if k == 0:
                for parent, child in self.tracks:
                    if (parent, child) not in self.skip:
                        times.append(chunk.times_ns)
                        parents.append(_repeated(parent, len(chunk)))
                        children.append(_repeated(child, len(chunk)))
        if not times:
            return np.zeros(0, object), np.zeros(0, object), np.zeros(0, np.int64)
        t = np.concatenate(times)
        order = np.argsort(t, kind="stable")
        return np.concatenate(parents)[order], np.concatenate(children)[order], t[order]

    def records(self, chunks: Sequence[SampleChunk | None]) -> TfRecords:
        """:meth:`rows` as dynamic rows (identity transforms: for the TF tree, not drawn)."""
        parents, children, times = self.rows(chunks)
        return _records(times, list(parents), list(children), False)

    def tf_rows(self, chunks: Iterable[Sequence[SampleChunk | None]]) -> TfRows:
        """:meth:`rows` of every stretch of a run, as :class:`TfRows` stamped when published."""
        parts = [self.rows(c) for c in chunks]
        if not parts:
            return TfRows(np.zeros(0, object), np.zeros(0, object), np.zeros(0, np.int64), np.zeros(0, np.int64))
        times = np.concatenate([p[2] for p in parts])
        return TfRows(np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]), times, times)

    def _moving(self, tree: KinematicTree) -> list[tuple[int, tuple[str, str]]]:
        out = []
        for m, name in enumerate(tree.moving):
            joint = tree.robot.joint(name)
            if (joint.parent, joint.child) not in self.skip:
                out.append((m, (joint.parent, joint.child)))
        return out


def motion_tree(tree: KinematicTree, source: Source, max_samples: int = 10_000) -> TfTree:
    """The TF tree of a generated motion (the tutorial's: what ``view_frames`` shows beside ``demo.launch.py``):
    the robot's frames and the motion's tracks, over the motion's span."""
    frames = RobotFrames((tree,), tuple(source.frames))
    rows = frames.tf_rows([c] for c in source.chunks(max_samples))
    span = (int(rows.receive_ns.min()), int(rows.receive_ns.max())) if len(rows) else (0, 0)
    return analyse(rows, frames.static_edges(), span_ns=span, end_word="the end of the run")


def _repeated(name: str, n: int) -> npt.NDArray[np.object_]:
    """``name`` ``n`` times (np.repeat of one: ~15x faster than ``np.full`` of an object array)."""
    return np.repeat(np.array([name], dtype=object), n)


def _records(times: I64, parents: list[str], children: list[str], static: bool) -> TfRecords:
    n = len(times)
    quat = np.zeros((n, 4))
    quat[:, 3] = 1.0
    return TfRecords(np.asarray(times, np.int64), tuple(parents), tuple(children), np.zeros((n, 3)), quat, static)
