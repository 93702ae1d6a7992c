"""Transforms as a bag recorded them (``/tf``, ``/tf_static``), logged as named frames like :mod:`r2d2_viz.viewer.scene`
and :mod:`r2d2_viz.viewer.tf_rows` log a robot's: ``/tf_static/<child>`` (static), rows on ``/tf`` (each naming its
frames, at their stamps), ``/tf_axes/<frame>`` for every frame and an arrow per edge (``/tf_arrows/<child>``,
in the parent frame; per row for moving edges).

Edges that the robot's URDF also defines are left out (the kinematics of the joint states draws them) — see
:func:`r2d2_viz.sources.tf_check.disagreement` for the check that they agree.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import rerun as rr

from r2d2_viz.sources.bag_tf import concatenate
from r2d2_viz.sources.base import Clock, SampleChunk, TfRecords
from r2d2_viz.sources.system.tf_robot import RobotFrames
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.columns import f32, send, tiled, time_array
from r2d2_viz.viewer.layout.fit import AXIS_LENGTH
from r2d2_viz.viewer.scene import ARROW_COLOR
from r2d2_viz.viewer.system.tf_graph import TfGraph
from r2d2_viz.viewer.tf_rows import arrow_columns, transform_columns

if TYPE_CHECKING:
    from r2d2_viz.sources.plan import RunPlan


class RecordedTf:
    """Logs recorded transforms chunk by chunk; remembers which frames already have axes and arrows."""

    def __init__(
        self,
        rec: rr.RecordingStream,
        *,
        clock: Clock,
        timeline: str = entities.TIMELINE,
        skip: set[tuple[str, str]] | None = None,
        axis_length: float = AXIS_LENGTH,
    ) -> None:
        self.rec, self.clock, self.timeline = rec, clock, timeline
        self.skip = skip or set()
        self.axis_length = axis_length
        self.frames: set[str] = set()
        self._arrow_edges: set[tuple[str, str]] = set()
        self.rows = 0
        self.graph: TfGraph | None = None
        """``--tf-tree``: the TF graph view, fed every row (the URDF's edges too)."""

    def log(self, records: TfRecords, *, graph: bool = True) -> None:
        """``records`` as transforms; fed to the graph too unless ``graph`` is False (they were, merged)."""
        if self.graph is not None and graph:
            self.graph.add(records)
        keep = np.array([(p, c) not in self.skip for p, c in zip(records.parents, records.children, strict=True)])
        if not keep.any():
            return
        index = np.flatnonzero(keep)
        parents = [records.parents[i] for i in index]
        children = [records.children[i] for i in index]
        translation, quat = f32(records.translation[index]), records.quat_xyzw[index]
        self._log_axes({*parents, *children})
        if records.static:
            self._log_static(parents, children, translation, quat)
        else:
            self._log_moving(records.times_ns[index], parents, children, translation, quat)
        self.rows += len(index)

    def _log_axes(self, frames: set[str]) -> None:
        for frame in sorted(frames - self.frames):
            self.rec.log(
                entities.tf_axes(frame),
                rr.CoordinateFrame(frame),
                rr.TransformAxes3D(self.axis_length, show_frame=False),
                static=True,
            )
        self.frames |= frames

    def _log_static(self, parents: list[str], children: list[str], translation: np.ndarray, quat: np.ndarray) -> None:
        latest = {child: i for i, child in enumerate(children)}  # the last one of each child wins, as in tf2
        for child, i in latest.items():
            self.rec.log(
                entities.tf_static(child),
                rr.Transform3D(
                    translation=translation[i],
                    quaternion=rr.Quaternion(xyzw=quat[i]),
                    parent_frame=parents[i],
                    child_frame=child,
                ),
                static=True,
            )
            if float(np.linalg.norm(translation[i])) > 0:
                self.rec.log(
                    entities.tf_arrow(child),
                    rr.CoordinateFrame(parents[i]),
                    rr.Arrows3D(origins=[translation[i]], vectors=[-translation[i]], colors=[ARROW_COLOR]),
                    static=True,
                )

    def _log_moving(
        self, times_ns: np.ndarray, parents: list[str], children: list[str], translation: np.ndarray, quat: np.ndarray
    ) -> None:
        times = time_array(times_ns, self.clock)
        columns = transform_columns(translation, f32(quat), tiled(parents, 1), tiled(children, 1))  # quat: xyzw
        send(self.rec, entities.TF, self.timeline, times, columns)
        child_array = np.array(children, dtype=object)
        for parent, child in sorted(set(zip(parents, children, strict=True))):
            rows = np.flatnonzero(child_array == child)
            if (parent, child) not in self._arrow_edges:
                self._arrow_edges.add((parent, child))
                self.rec.log(
                    entities.tf_arrow(child),
                    rr.CoordinateFrame(parent),
                    rr.Arrows3D.from_fields(colors=[ARROW_COLOR]),
                    static=True,
                )
            arrows = arrow_columns(translation[rows], -translation[rows])
            send(self.rec, entities.tf_arrow(child), self.timeline, time_array(times_ns[rows], self.clock), arrows)


class TfFeed:
    """Recorded moving transforms handed to a :class:`RecordedTf` in time order, as far as a replay has got: a
    replay :meth:`push` es each stretch it reads, and :meth:`until` logs what is due.

    With the TF graph (``--tf-tree``) and a ``plan`` whose robots come from descriptions, the graph also gets the
    frames the kinematics draws (:class:`~r2d2_viz.sources.system.tf_robot.RobotFrames`: fixed joints once, moving
    joints at each joint-states sample), merged in time order with the recorded rows (not logged as transforms)."""

    def __init__(self, recorded: RecordedTf, plan: RunPlan | None = None) -> None:
        self.recorded = recorded
        self._pending: deque[TfRecords] = deque()
        self._robot: deque[TfRecords] = deque()
        self.logged = 0
        self.robot = robot_frames(plan) if plan is not None and recorded.graph is not None else None
        if self.robot is not None and recorded.graph is not None and plan is not None:
            start = plan.replay.span[0] if plan.replay is not None else 0
            recorded.graph.add(self.robot.static_records(start))

    def push(self, records: TfRecords | None, joints: Sequence[SampleChunk | None] = ()) -> None:
        """Transforms just read (sorted by time here: header stamps need not be in order), and the joint states of
        the same stretch (each robot's: the graph's robot frames)."""
        if self.robot is not None and joints and len(robot := self.robot.records(joints)):
            self._robot.append(robot)
        if records is None or len(records) == 0:
            return
        times = records.times_ns
        if len(times) > 1 and not bool(np.all(times[1:] >= times[:-1])):
            records = records.rows(np.argsort(times, kind="stable"))
        self._pending.append(records)

    @property
    def next_time_ns(self) -> int | None:
        """The time of the next record not logged yet (None: none pending)."""
        return int(self._pending[0].times_ns[0]) if self._pending else None

    def until(self, time_ns: int | None = None) -> None:
        """Log the pending records up to ``time_ns`` (inclusive; all of them when None)."""
        parts = _due(self._pending, time_ns)
        graph = self.recorded.graph
        merged = graph is not None and self.robot is not None  # the graph gets recorded and robot rows as one
        if merged and graph is not None and (both := concatenate([*parts, *_due(self._robot, time_ns)])):
            graph.add(both.rows(np.argsort(both.times_ns, kind="stable")))
        for part in parts:
            self.recorded.log(part, graph=not merged)
            self.logged += len(part)


def _due(pending: deque[TfRecords], time_ns: int | None) -> list[TfRecords]:
    """The records of ``pending`` up to ``time_ns`` (inclusive; all when None), taken off it."""
    out = []
    while pending:
        r = pending[0]
        stop = len(r) if time_ns is None else int(np.searchsorted(r.times_ns, time_ns, side="right"))
        if stop == 0:
            break
        part = r if stop == len(r) else r.rows(np.arange(stop))
        out.append(TfRecords(part.times_ns, part.parents, part.children, part.translation, part.quat_xyzw))
        if stop < len(r):
            pending[0] = r.rows(np.arange(stop, len(r)))
            break
        pending.popleft()
    return out


def robot_frames(plan: RunPlan) -> RobotFrames | None:
    """The frames the run's kinematics draws (its robots', and a generated motion's tracks), for the TF graph."""
    trees = tuple(r.tree for r in plan.robots) or ((plan.tree,) if plan.tree is not None else ())
    if not trees:
        return None
    tracks = tuple(plan.source.frames) if plan.source is not None else ()
    return RobotFrames(trees, tracks, plan.skip_edges)
