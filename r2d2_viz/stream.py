"""Log a moving robot to Rerun the way ROS would put it on /tf, /tf_static and /robot_description.

Entity layout (every name is a URDF link or joint name, escaped for entity paths):

* ``/tf_static/<child>`` — fixed (and planar) joints: one static ``Transform3D(parent_frame, child_frame)``;
* ``/tf/<child>`` — moving joints and ``odom → <root>``: one ``Transform3D`` per frame;
* ``/robot/visual/<link>/<i>``, ``/robot/collision/<link>/<i>`` — ``Mesh3D`` in the link's named frame
  (``CoordinateFrame``), shape origin baked into the vertices;
* ``/tf_axes/<frame>`` — ``TransformAxes3D`` for every frame (RViz TF "Show Axes"; names off);
* ``/tf_arrows/<child>`` — an arrow from each child frame's origin to its parent's (RViz "Show Arrows");
* ``/joints/limited/<joint>/value|lower|upper`` — values of joints with limits, and the limits;
* ``/joints/continuous/<joint>`` — values of continuous joints (they grow without bound: own plot);
* ``/warnings`` — ``TextLog`` lines, e.g. a joint leaving its limits.

Named frames are the URDF link names plus ``odom``. Quaternions enter Rerun as ``xyzw``.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pyarrow as pa
import rerun as rr

from .kinematics import KinematicTree, moving_values, transforms_from_values
from .meshes import shape_mesh
from .model import Rgba, Shape
from .motion import Motion, MotionChunk

APP_ID = "r2d2_viz"
TIMELINE = "time"
ODOM = "odom"
AXIS_LENGTH = 0.1
"""RViz's TF display draws axes 0.1 m long at marker scale 1."""
ARROW_COLOR = (255, 0, 255)
COLLISION_COLOR = (255, 140, 0, 160)
DEFAULT_VISUAL_COLOR = (204, 204, 204, 255)
LIMIT_LOG_PERIOD_S = 1.0
"""How often (in recording time) live runs repeat the constant limit lines, so they span the plot."""

F64 = npt.NDArray[np.float64]
Warn = Callable[[str], None]


def path(*parts: str) -> str:
    """An entity path from unescaped parts (link names may hold spaces, slashes, non-ASCII)."""
    return "/" + "/".join(rr.escape_entity_path_part(p) for p in parts)


def _rgba8(rgba: Rgba | None, default: tuple[int, ...]) -> tuple[int, ...]:
    if rgba is None:
        return default
    return tuple(round(min(max(c, 0.0), 1.0) * 255) for c in rgba)


def _time_column(frames: npt.NDArray[np.int64], rate: float) -> rr.TimeColumn:
    nanos = np.rint(frames * (1e9 / rate)).astype(np.int64)
    return rr.TimeColumn(TIMELINE, duration=nanos.astype("timedelta64[ns]"))


def _repeated(text: str, n: int) -> pa.StringArray:
    """``[text] * n`` as an Arrow string array, built from two buffers (no per-row Python strings).

    Rerun takes an Arrow array of its own type as is; a Python list would be converted row by row.
    The column itself is unchanged: every row still holds the name."""
    data = text.encode()
    offsets = np.arange(n + 1, dtype=np.int64) * len(data)
    if offsets[-1] > np.iinfo(np.int32).max:  # cannot happen for the chunk sizes used; stay correct anyway
        return pa.array([text] * n, type=pa.utf8())
    return pa.StringArray.from_buffers(n, pa.py_buffer(offsets.astype(np.int32)), pa.py_buffer(data * n))


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
        self._value_path = [
            path("joints", "limited", name, "value") if name in self._limits else path("joints", "continuous", name)
            for name in self.tree.moving
        ]
        self._reported: set[str] = set()
        self._next_limit_time = 0.0
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
            else:
                self._log_arrow_style(self._moving_parent[m], self._moving_child[m])
        if self.motion.moves_root:
            self._log_arrow_style(ODOM, robot.root)
        else:
            rec.log(
                path("tf", robot.root),
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
        for m, name in enumerate(tree.moving):
            color = palette[m]
            rec.log(self._value_path[m], rr.SeriesLines(colors=[color], names=[name], widths=[2.0]), static=True)
            if name in self._limits:
                faded = (*color[:3], 140)
                for bound in ("lower", "upper"):
                    rec.log(
                        path("joints", "limited", name, bound),
                        rr.SeriesLines(colors=[faded], names=[f"{name} {bound} limit"], widths=[1.0]),
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

    def _log_arrow_style(self, parent: str, child: str) -> None:
        self.rec.log(
            path("tf_arrows", child),
            rr.CoordinateFrame(parent),
            rr.Arrows3D.from_fields(colors=[ARROW_COLOR]),
            static=True,
        )

    def _log_shape(self, entity: str, link: str, shape: Shape, visual: bool) -> None:
        try:
            mesh = shape_mesh(shape)
        except ValueError as exc:
            self.warn(f"{self.tree.robot.source}: link {link!r}: {exc}; shape skipped")
            return
        color = _rgba8(shape.rgba, DEFAULT_VISUAL_COLOR) if visual else COLLISION_COLOR
        self.rec.log(
            entity,
            rr.CoordinateFrame(link),
            rr.Mesh3D(
                vertex_positions=mesh.vertices,
                vertex_normals=mesh.normals,
                triangle_indices=mesh.triangles,
                albedo_factor=color,
            ),
            static=True,
        )

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
        send each frame when it is due, so a frame costs one slice and one send per entity.
        """
        tree = self.tree
        n = len(chunk.frame)
        values = moving_values(tree, chunk.positions[:, self._order])
        translation, quat = transforms_from_values(tree, values)
        entities: list[tuple[str, list[tuple[rr.ComponentDescriptor, pa.Array]]]] = []
        for m, child in enumerate(self._moving_child):
            entities.append(self._transform_columns(self._moving_parent[m], child, translation[:, m], quat[:, m]))
            if self._prismatic[m]:
                entities.append(_arrow_columns(child, translation[:, m]))
        if chunk.odom_translation is not None and chunk.odom_quat_xyzw is not None:
            root = tree.robot.root
            entities.append(self._transform_columns(ODOM, root, chunk.odom_translation, chunk.odom_quat_xyzw))
            entities.append(_arrow_columns(root, chunk.odom_translation))
        for m in range(len(tree.moving)):
            entities.append((self._value_path[m], _encoded(rr.Scalars.columns(scalars=values[:, m]))))
        time = _time_column(chunk.frame, self.rate).as_arrow_array()
        return PreparedFrames(chunk.frame, values, time, entities) if n else PreparedFrames.empty(values)

    def send(self, frames: PreparedFrames, start: int = 0, stop: int | None = None) -> None:
        """Log frames ``start … stop-1`` of a prepared block (all by default), one chunk per entity."""
        stop = len(frames.frame) if stop is None else min(stop, len(frames.frame))
        if start >= stop:
            return
        n = stop - start
        whole = start == 0 and stop == len(frames.frame)
        times = [_Index(TIMELINE, frames.time if whole else frames.time.slice(start, n))]
        for entity, columns in frames.entities:
            self.rec.send_columns(
                entity,
                indexes=times,
                columns=[_Column(d, a if whole else a.slice(start, n)) for d, a in columns],
            )
        frame = frames.frame[start:stop]
        self._check_limits(frame, frames.values[start:stop])
        self._last_frame = int(frame[-1])
        end_time = self._last_frame / self.rate
        if frame[0] == 0 or end_time >= self._next_limit_time:
            self._log_limits(float(frame[0]) / self.rate if frame[0] == 0 else end_time)
            self._next_limit_time = end_time + LIMIT_LOG_PERIOD_S

    def _transform_columns(
        self, parent: str, child: str, t: F64, q: F64
    ) -> tuple[str, list[tuple[rr.ComponentDescriptor, pa.Array]]]:
        """``/tf/<child>``: every row names its frames (Rerun attaches a row to a frame only if the row says so)."""
        n = len(t)
        columns = rr.Transform3D.columns(
            translation=t,
            quaternion=q,
            parent_frame=_repeated(parent, n),
            child_frame=_repeated(child, n),
        )
        return path("tf", child), _encoded(columns)

    def finish(self) -> None:
        """Draw the limit lines up to the last frame."""
        if self._last_frame >= 0:
            self._log_limits(self._last_frame / self.rate)

    def _log_limits(self, time_s: float) -> None:
        self.rec.set_time(TIMELINE, duration=time_s)
        for name, (lower, upper) in self._limits.items():
            self.rec.log(path("joints", "limited", name, "lower"), rr.Scalars(lower))
            self.rec.log(path("joints", "limited", name, "upper"), rr.Scalars(upper))

    def _check_limits(self, frame: npt.NDArray[np.int64], values: F64) -> None:
        for m, name in enumerate(self.tree.moving):
            if name in self._reported or name not in self._limits:
                continue
            lower, upper = self._limits[name]
            outside = np.flatnonzero((values[:, m] < lower) | (values[:, m] > upper))
            if len(outside) == 0:
                continue
            k = outside[0]
            self._reported.add(name)
            t = float(frame[k]) / self.rate
            message = (
                f"joint {name!r} left its URDF limits [{lower:g}, {upper:g}] at t={t:.3f} s "
                f"(value {values[k, m]:.4g}); shown unclamped, like robot_state_publisher"
            )
            self.warn(message)
            self.rec.set_time(TIMELINE, duration=t)
            self.rec.log("/warnings", rr.TextLog(message, level=rr.TextLogLevel.WARN))


@dataclass(frozen=True, eq=False)
class PreparedFrames:
    """Frames encoded for Rerun by :meth:`RobotStream.prepare`: per entity, its Arrow list columns."""

    frame: npt.NDArray[np.int64]  # (n,)
    values: F64  # (n, M) moving-joint values, for the limit checks
    time: pa.Array  # (n,) durations on the ``time`` timeline
    entities: list[tuple[str, list[tuple[rr.ComponentDescriptor, pa.Array]]]]

    @staticmethod
    def empty(values: F64) -> PreparedFrames:
        return PreparedFrames(np.zeros(0, dtype=np.int64), values, pa.array([], pa.duration("ns")), [])


class _Index:
    """A time column whose Arrow array is already built (``rr.TimeColumnLike``)."""

    __slots__ = ("_array", "_timeline")

    def __init__(self, timeline: str, array: pa.Array) -> None:
        self._timeline, self._array = timeline, array

    def timeline_name(self) -> str:
        return self._timeline

    def as_arrow_array(self) -> pa.Array:
        return self._array


class _Column(rr.ComponentColumn):
    """A component column whose Arrow list array (one list per row) is already built.

    ``rr.ComponentColumn`` would rebuild the list array from its batch and offsets on every send;
    ``send_columns`` only asks a column for its descriptor and its list array."""

    def __init__(self, descriptor: rr.ComponentDescriptor, array: pa.Array) -> None:
        self.descriptor = descriptor
        self._array = array

    def as_arrow_array(self) -> pa.Array:
        return self._array


def _encoded(columns: rr.ComponentColumnList) -> list[tuple[rr.ComponentDescriptor, pa.Array]]:
    return [(c.component_descriptor(), c.as_arrow_array()) for c in columns]


def _arrow_columns(child: str, t_parent_child: F64) -> tuple[str, list[tuple[rr.ComponentDescriptor, pa.Array]]]:
    """``/tf_arrows/<child>``: the arrow from the child frame's origin back to its parent's."""
    return path("tf_arrows", child), _encoded(rr.Arrows3D.columns(origins=t_parent_child, vectors=-t_parent_child))


def _palette(n: int) -> list[tuple[int, int, int, int]]:
    """Distinct, bright colours for the joint plot (golden-angle hues)."""
    colors = []
    for i in range(n):
        h = (i * 0.381966) % 1.0
        r, g, b = (0.5 + 0.5 * math.cos(2 * math.pi * (h + k / 3)) for k in (0, 1, 2))
        colors.append((int(60 + 195 * r), int(60 + 195 * g), int(60 + 195 * b), 255))
    return colors
