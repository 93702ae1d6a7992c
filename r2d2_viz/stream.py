"""Log a moving robot to Rerun the way ROS would put it on /tf, /tf_static and /robot_description.

Entity layout (every name is a URDF link or joint name, escaped for entity paths):

* ``/tf_static/<child>`` — fixed (and planar) joints, and ``odom → <root>`` when the root stays put: one
  static ``Transform3D(parent_frame, child_frame)`` each;
* ``/tf`` — every moving joint and a moving ``odom → <root>``: one ``Transform3D`` row per joint per frame,
  each row naming its frames (one entity, like the /tf topic: Rerun resolves every child frame of it);
  the TF arrows that move (prismatic joints, a moving root) ride along in the first row of each frame,
  drawn in ``odom`` (``/tf``'s ``CoordinateFrame``), so a frame is one chunk;
* ``/robot/visual/<link>/<i>``, ``/robot/collision/<link>/<i>`` — ``Mesh3D`` in the link's named frame
  (``CoordinateFrame``), shape origin baked into the vertices;
* ``/tf_axes/<frame>`` — ``TransformAxes3D`` for every frame (RViz TF "Show Axes"; names off);
* ``/tf_arrows/<child>`` — an arrow from each child frame's origin to its parent's (RViz "Show Arrows"),
  static in the parent frame (the arrows that move are on ``/tf``);
* ``/joints/limited`` — values of the joints with limits, one series each; ``/joints/limited/limits`` their
  lower and upper limits, two series per joint (one entity: a row for every limit line is one chunk);
* ``/joints/continuous`` — values of continuous joints (they grow without bound: their own plot);
* ``/warnings`` — ``TextLog`` lines, e.g. a joint leaving its limits.

Named frames are the URDF link names plus ``odom``. Quaternions enter Rerun as ``xyzw``.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pyarrow as pa
import rerun as rr
from rerun_bindings import send_arrow_chunk as _send_arrow_chunk

from .kinematics import KinematicTree, link_positions, moving_values, transforms_from_values
from .meshes import MeshCache
from .model import Rgba, Shape
from .motion import Motion, MotionChunk
from .transforms import quat_to_matrix
from .visuals import log_shape

APP_ID = "r2d2_viz"
TIMELINE = "time"
ODOM = "odom"
AXIS_LENGTH = 0.1
"""RViz's TF display draws axes 0.1 m long at marker scale 1."""
ARROW_COLOR = (255, 0, 255)
COLLISION_COLOR = (255, 140, 0, 160)
DEFAULT_VISUAL_COLOR = (204, 204, 204, 255)
PLOT_PERIOD_S = 0.5
"""Live runs send plot values twice a second (each with its own timestamp), transforms every frame."""
LIMIT_LOG_PERIOD_S = 1.0
"""How often (in recording time) live runs repeat the constant limit lines, so they span the plot; they
go out with the plot values, so a live frame wakes Rerun's threads once (see :meth:`RobotStream.send`)."""

F64 = npt.NDArray[np.float64]
Warn = Callable[[str], None]


def path(*parts: str) -> str:
    """An entity path from unescaped parts (link names may hold spaces, slashes, non-ASCII)."""
    return "/" + "/".join(rr.escape_entity_path_part(p) for p in parts)


LIMITS_ENTITY = path("joints", "limited", "limits")


def _rgba8(rgba: Rgba | None, default: tuple[int, ...]) -> tuple[int, ...]:
    if rgba is None:
        return default
    return tuple(round(min(max(c, 0.0), 1.0) * 255) for c in rgba)


def _tiled(texts: list[str], n: int) -> pa.StringArray:
    """``texts * n`` as an Arrow string array, built from two buffers (no per-row Python strings).

    Rerun takes an Arrow array of its own type as is; a Python list would be converted row by row.
    The column itself is unchanged: every row still holds its name."""
    encoded = [t.encode() for t in texts]
    lengths = np.tile(np.array([len(e) for e in encoded], dtype=np.int64), n)
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    if offsets[-1] > np.iinfo(np.int32).max:  # cannot happen for the chunk sizes used; stay correct anyway
        return pa.array(texts * n, type=pa.utf8())
    data = b"".join(encoded) * n
    return pa.StringArray.from_buffers(len(lengths), pa.py_buffer(offsets.astype(np.int32)), pa.py_buffer(data))


def _stderr(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr, flush=True)


@dataclass
class RobotStream:
    """Logs one robot and its motion to a recording: :meth:`log_static` once, then :meth:`log_chunk`."""

    rec: rr.RecordingStream
    tree: KinematicTree
    motion: Motion
    rate: float
    warn: Warn = _stderr

    def __post_init__(self) -> None:
        robot = self.tree.robot
        joints = {j.name: j for j in robot.joints}
        self._moving_child = [joints[name].child for name in self.tree.moving]
        self._moving_parent = [joints[name].parent for name in self.tree.moving]
        self._prismatic = [joints[name].type == "prismatic" for name in self.tree.moving]
        self._column = {name: i for i, name in enumerate(self.motion.joints)}
        assert set(self.motion.joints) == set(self.tree.actuated), "motion and robot disagree on joints"
        self._order = [self._column[name] for name in self.tree.actuated]
        self._limits = self.tree.limits
        limited = [m for m, name in enumerate(self.tree.moving) if name in self._limits]
        continuous = [m for m, name in enumerate(self.tree.moving) if name not in self._limits]
        self._plots = [
            (path("joints", kind), np.array(ms, dtype=np.intp))
            for kind, ms in (("limited", limited), ("continuous", continuous))
            if ms
        ]
        self._tf_parents = [*self._moving_parent, *([ODOM] if self.motion.moves_root else [])]
        self._tf_children = [*self._moving_child, *([robot.root] if self.motion.moves_root else [])]
        # rows of /tf whose child origin moves in its parent: prismatic joints and a moving root
        self._moving_arrows = [
            r for r in range(len(self._tf_children)) if r >= len(self._prismatic) or self._prismatic[r]
        ]
        index = {name: i for i, name in enumerate(self.tree.links)}  # odom is no link: -1
        self._arrow_ends = [
            (index[self._tf_children[r]], index.get(self._tf_parents[r], -1)) for r in self._moving_arrows
        ]
        self._arrow_links = sorted({i for pair in self._arrow_ends for i in pair if i >= 0})
        self._reported: set[str] = set()
        bounds = [bound for name in self.tree.moving if name in self._limits for bound in self._limits[name]]
        self._limit_row = dict(_encoded(rr.Scalars.columns(scalars=bounds).partition([len(bounds)])))
        self._native = self.rec.to_native()
        self._pending_block: PreparedFrames | None = None
        self._plot_from = self._sent_to = 0
        self._next_limit_time = 0.0
        self._plot_every = max(1, round(PLOT_PERIOD_S * self.rate))
        self._last_frame = -1

    # --- static ----------------------------------------------------------------------------------

    def log_static(self) -> None:
        """Robot description: fixed transforms, meshes, TF axes and arrows, plot styling."""
        rec, tree, robot = self.rec, self.tree, self.tree.robot
        for message in (*robot.warnings, *tree.warnings):
            self.warn(message)
            rec.log("/warnings", rr.TextLog(message, level=rr.TextLogLevel.WARN), static=True)

        translation, quat = tree.static_translation_quat()
        for i, name in enumerate(tree.static):
            joint = robot.joint(name)
            rec.log(
                path("tf_static", joint.child),
                rr.Transform3D(
                    translation=translation[i],
                    quaternion=rr.Quaternion(xyzw=quat[i]),
                    parent_frame=joint.parent,
                    child_frame=joint.child,
                ),
                static=True,
            )
            self._log_arrow_static(joint.parent, joint.child, translation[i])
        # Revolute/continuous joints never move their child's origin: their arrow is static too.
        # Prismatic joints and a moving root get their arrows per frame (see _arrow_columns).
        for m in range(len(tree.moving)):
            if not self._prismatic[m]:
                self._log_arrow_static(self._moving_parent[m], self._moving_child[m], tree.moving_origin_t[m])
        if self._moving_arrows:
            rec.log(
                path("tf"),
                rr.CoordinateFrame(ODOM),
                rr.Arrows3D.from_fields(colors=[ARROW_COLOR] * len(self._moving_arrows)),
                static=True,
            )
        if not self.motion.moves_root:
            rec.log(
                path("tf_static", robot.root),
                rr.Transform3D(translation=[0.0, 0.0, 0.0], parent_frame=ODOM, child_frame=robot.root),
                static=True,
            )

        for frame in (ODOM, *tree.links):
            rec.log(
                path("tf_axes", frame),
                rr.CoordinateFrame(frame),
                rr.TransformAxes3D(AXIS_LENGTH, show_frame=False),
                static=True,
            )

        for link in robot.links:
            for kind, shapes in (("visual", link.visuals), ("collision", link.collisions)):
                for i, shape in enumerate(shapes):
                    self._log_shape(path("robot", kind, link.name, str(i)), link.name, shape, kind == "visual")

        palette = _palette(len(tree.moving))
        for entity, ms in self._plots:
            names = [tree.moving[m] for m in ms]
            rec.log(
                entity,
                rr.SeriesLines(colors=[palette[m] for m in ms], names=names, widths=[2.0] * len(ms)),
                static=True,
            )
        limited = [(m, name) for m, name in enumerate(tree.moving) if name in self._limits]
        if limited:  # lower, upper for each joint, in the order of self._limit_row
            rec.log(
                LIMITS_ENTITY,
                rr.SeriesLines(
                    colors=[(*palette[m][:3], 140) for m, _ in limited for _ in range(2)],
                    names=[f"{name} {bound} limit" for _, name in limited for bound in ("lower", "upper")],
                    widths=[1.0] * (2 * len(limited)),
                ),
                static=True,
            )

    def _log_arrow_static(self, parent: str, child: str, t_parent_child: F64) -> None:
        if float(np.linalg.norm(t_parent_child)) == 0.0:
            return  # coincident frames: RViz draws no arrow either
        self.rec.log(
            path("tf_arrows", child),
            rr.CoordinateFrame(parent),
            rr.Arrows3D(origins=[t_parent_child], vectors=[-np.asarray(t_parent_child)], colors=[ARROW_COLOR]),
            static=True,
        )

    def _log_shape(self, entity: str, link: str, shape: Shape, visual: bool) -> None:
        # wip-10m: temporary wiring to r2d2_viz.visuals.log_shape until the lead's split of this module
        cache = self.__dict__.get("_mesh_cache") or self.__dict__.setdefault("_mesh_cache", MeshCache())
        source = self.tree.robot.source
        log_shape(self.rec, entity, link, shape, visual=visual, cache=cache, warn=lambda m: self.warn(f"{source}: {m}"))

    # --- per frame ---------------------------------------------------------------------------------

    def log_chunk(self, chunk: MotionChunk) -> None:
        """Log consecutive frames: moving joint transforms, odom → root, arrows, joint values.

        One ``send_columns`` per entity for the whole chunk (see :meth:`prepare` and :meth:`send`).
        """
        self.send(self.prepare(chunk))

    def prepare(self, chunk: MotionChunk) -> PreparedFrames:
        """Compute and encode frames for :meth:`send` (nothing is logged yet).

        Everything is vectorised over the chunk: the Arrow columns are built once, and sending
        any run of its frames later only slices them. Live runs prepare a block of frames ahead and
        send each frame when it is due, so a frame costs a slice and one send — a frame is one chunk
        (``/tf``, arrows included; plots go out a few times a second): Rerun's cost is per chunk.
        """
        tree = self.tree
        n = len(chunk.frame)
        values = moving_values(tree, chunk.positions[:, self._order])
        if n == 0:
            return PreparedFrames.empty(values)
        translation, quat = transforms_from_values(tree, values)  # (n, M, 3), (n, M, 4)
        arrows = self._moving_arrow_columns(chunk, translation, quat) if self._moving_arrows else []
        if chunk.odom_translation is not None and chunk.odom_quat_xyzw is not None:
            translation = np.concatenate([translation, chunk.odom_translation[:, None]], axis=1)
            quat = np.concatenate([quat, chunk.odom_quat_xyzw[:, None]], axis=1)
        rows = translation.shape[1]  # transforms per frame, in self._tf_children order
        entities: list[_Entity] = []
        if rows:
            columns = rr.Transform3D.columns(
                translation=translation.reshape(-1, 3),
                quaternion=quat.reshape(-1, 4),
                parent_frame=_tiled(self._tf_parents, n),
                child_frame=_tiled(self._tf_children, n),
            )
            spread = [(d, _first_of_every(a, rows)) for d, a in arrows]  # arrows on each frame's first row
            entities.append(_Entity(path("tf"), rows, [*_encoded(columns), *spread]))
        for entity, ms in self._plots:
            scalars = rr.Scalars.columns(scalars=values[:, ms].reshape(-1)).partition(np.full(n, len(ms)))
            entities.append(_Entity(entity, 1, _encoded(scalars), plot=True))
        nanos = np.rint(chunk.frame * (1e9 / self.rate)).astype(np.int64)
        times = {r: pa.array(np.repeat(nanos, r).astype("timedelta64[ns]")) for r in {e.rows for e in entities}}
        return PreparedFrames(chunk.frame, values, times, entities, self._outside(values))

    def _outside(self, values: F64) -> dict[int, int]:
        """Each joint not yet reported that leaves its limits in this block → the first frame it is outside
        (an index into the block). Checked once a block, vectorised; reported when that frame is sent."""
        pending = [m for m, name in enumerate(self.tree.moving) if name in self._limits and name not in self._reported]
        if not pending:
            return {}
        lower = np.array([self._limits[self.tree.moving[m]][0] for m in pending])
        upper = np.array([self._limits[self.tree.moving[m]][1] for m in pending])
        block = values[:, pending]
        out = (block < lower) | (block > upper)  # (n, pending)
        return {pending[j]: int(out[:, j].argmax()) for j in np.flatnonzero(out.any(axis=0))}

    def _moving_arrow_columns(
        self, chunk: MotionChunk, translation: F64, quat: F64
    ) -> list[tuple[rr.ComponentDescriptor, pa.Array]]:
        """The arrows that move, one row per frame: from each moving child's origin to its parent's, in ``odom``."""
        n = len(chunk.frame)
        T_odom_root = None
        if chunk.odom_translation is not None and chunk.odom_quat_xyzw is not None:
            T_odom_root = np.zeros((n, 4, 4))
            T_odom_root[:, :3, :3] = quat_to_matrix(chunk.odom_quat_xyzw)
            T_odom_root[:, :3, 3] = chunk.odom_translation
        at = link_positions(self.tree, translation, quat, self._arrow_links, T_fixed_root=T_odom_root)
        odom = np.zeros((n, 3))
        child = np.stack([at[c] for c, _ in self._arrow_ends], axis=1)  # (n, k, 3)
        parent = np.stack([at[p] if p >= 0 else odom for _, p in self._arrow_ends], axis=1)
        k = len(self._arrow_ends)
        arrows = rr.Arrows3D.columns(origins=child.reshape(-1, 3), vectors=(parent - child).reshape(-1, 3))
        return _encoded(arrows.partition(np.full(n, k)))

    def send(self, frames: PreparedFrames, start: int = 0, stop: int | None = None) -> None:
        """Log frames ``start … stop-1`` of a prepared block (all by default), one chunk per entity.

        Transforms and arrows go out with every call. Plot values, when frames come one at a time (live
        runs), are gathered and sent every ``PLOT_PERIOD_S`` of robot time, and when the block ends:
        every value keeps its own timestamp, the plot just fills in a few times a second — Rerun's cost
        is per chunk, and this keeps a 30 Hz live run within a few percent of a core.
        """
        n = len(frames.frame)
        stop = n if stop is None else min(stop, n)
        if start >= stop:
            return
        if frames is not self._pending_block:
            self._flush_plots()
            self._pending_block, self._plot_from = frames, start
        for entity in frames.entities:
            if not entity.plot:
                self._send_rows(frames, entity, start, stop)
        self._sent_to = stop
        if stop == n or stop - self._plot_from >= self._plot_every:
            self._flush_plots()
        for m, k in frames.outside.items():
            if start <= k < stop:
                self._report_outside(m, int(frames.frame[k]), float(frames.values[k, m]))
        self._last_frame = int(frames.frame[stop - 1])

    def _flush_plots(self) -> None:
        """Send the plot values of the frames sent so far that have not been plotted yet, and the limit
        lines: at the first frame, then every ``LIMIT_LOG_PERIOD_S`` (in batch runs: once a chunk)."""
        frames = self._pending_block
        if frames is None or self._plot_from >= self._sent_to:
            return
        for entity in frames.entities:
            if entity.plot:
                self._send_rows(frames, entity, self._plot_from, self._sent_to)
        first, last = int(frames.frame[self._plot_from]), int(frames.frame[self._sent_to - 1])
        self._plot_from = self._sent_to
        end_time = last / self.rate
        if first == 0 or end_time >= self._next_limit_time:
            self._log_limits(0.0 if first == 0 else end_time)
            self._next_limit_time = end_time + LIMIT_LOG_PERIOD_S

    def _send_rows(self, frames: PreparedFrames, entity: _Entity, start: int, stop: int) -> None:
        """``rec.send_columns`` for prebuilt Arrow columns, minus its per-call Python checks.

        The columns were built by Rerun's own ``…columns()`` and sliced here, so they are valid by
        construction; calling the binding that ``send_columns`` ends in, directly, halves the cost of a live
        frame. (rerun-sdk is pinned to 0.41: this is the same call its ``send_columns`` makes.)"""
        time = frames.times[entity.rows]
        if start == 0 and stop == len(frames.frame):
            timelines, components = {TIMELINE: time}, dict(entity.columns)
        else:
            first, count = start * entity.rows, (stop - start) * entity.rows
            timelines = {TIMELINE: time.slice(first, count)}
            components = {d: a.slice(first, count) for d, a in entity.columns}
        _send_arrow_chunk(entity.path, timelines=timelines, components=components, recording=self._native)

    def finish(self) -> None:
        """Send what is pending and draw the limit lines up to the last frame."""
        self._flush_plots()
        if self._last_frame >= 0:
            self._log_limits(self._last_frame / self.rate)

    def _log_limits(self, time_s: float) -> None:
        """One row on every limit line at ``time_s``: one chunk, encoded once (a robot with a thousand limited
        joints has two thousand lines; a chunk per line made the cost of a frame grow with their square)."""
        if not self._limits:
            return
        time = pa.array(np.array([round(time_s * 1e9)], dtype="timedelta64[ns]"))
        _send_arrow_chunk(LIMITS_ENTITY, timelines={TIMELINE: time}, components=self._limit_row, recording=self._native)

    def _report_outside(self, m: int, frame: int, value: float) -> None:
        """Warn, once per joint, that moving joint ``m`` is outside its limits at ``frame``."""
        name = self.tree.moving[m]
        if name in self._reported:
            return
        self._reported.add(name)
        lower, upper = self._limits[name]
        t = frame / self.rate
        message = (
            f"joint {name!r} left its URDF limits [{lower:g}, {upper:g}] at t={t:.3f} s "
            f"(value {value:.4g}); shown unclamped, like robot_state_publisher"
        )
        self.warn(message)
        self.rec.set_time(TIMELINE, duration=t)
        self.rec.log("/warnings", rr.TextLog(message, level=rr.TextLogLevel.WARN))


@dataclass(frozen=True, eq=False)
class _Entity:
    """One entity's columns for a block of frames: ``rows`` rows per frame (``/tf`` has one per joint)."""

    path: str
    rows: int
    columns: list[tuple[rr.ComponentDescriptor, pa.Array]]
    plot: bool = False
    """Plot data: in live runs sent every ``PLOT_PERIOD_S`` rather than every frame (see :meth:`send`)."""


@dataclass(frozen=True, eq=False)
class PreparedFrames:
    """Frames encoded for Rerun by :meth:`RobotStream.prepare`: per entity, its Arrow list columns."""

    frame: npt.NDArray[np.int64]  # (n,)
    values: F64  # (n, M) moving-joint values, for the limit checks
    times: dict[int, pa.Array]  # rows per frame → the ``time`` column, each frame's time repeated that often
    entities: list[_Entity]
    outside: dict[int, int] = field(default_factory=dict)
    """Moving joint → first frame (an index into ``frame``) it is outside its limits, for joints not yet reported."""

    @staticmethod
    def empty(values: F64) -> PreparedFrames:
        return PreparedFrames(np.zeros(0, dtype=np.int64), values, {}, [])


def _encoded(columns: rr.ComponentColumnList) -> list[tuple[rr.ComponentDescriptor, pa.Array]]:
    return [(c.component_descriptor(), c.as_arrow_array()) for c in columns]


def _first_of_every(lists: pa.ListArray, rows: int) -> pa.ListArray:
    """``lists`` (one list per frame) spread over ``rows`` rows per frame: each frame's list on its first
    row, null on the others — a null cell is no data, so a query at that time finds the first row's."""
    if rows == 1:
        return lists
    offsets = lists.offsets.to_numpy()
    spread = np.empty(len(lists) * rows + 1, dtype=offsets.dtype)
    spread[0] = offsets[0]
    spread[1:] = np.repeat(offsets[1:], rows)
    null = np.ones((len(lists), rows), dtype=bool)
    null[:, 0] = False
    return pa.ListArray.from_arrays(pa.array(spread), lists.values, type=lists.type, mask=pa.array(null.reshape(-1)))


def _palette(n: int) -> list[tuple[int, int, int, int]]:
    """Distinct, bright colours for the joint plot (golden-angle hues)."""
    colors = []
    for i in range(n):
        h = (i * 0.381966) % 1.0
        r, g, b = (0.5 + 0.5 * math.cos(2 * math.pi * (h + k / 3)) for k in (0, 1, 2))
        colors.append((int(60 + 195 * r), int(60 + 195 * g), int(60 + 195 * b), 255))
    return colors
