"""A JointState's efforts as RViz's Effort display draws them: at each revolute joint of the robot model, an arc
around the joint axis whose radius grows with the effort, coloured by it, and an arrow head at its end showing the
effort's sense.

Transcribed from ``rviz_default_plugins/displays/effort/effort_display.cpp`` and
``rviz_rendering/src/rviz_rendering/objects/effort_visual.cpp`` (ros2/rviz):

- only ``revolute`` joints (continuous ones have no effort limit), drawn in the joint's child link frame, turned by
  ``q = Quaternion(axis × z, angle(axis, z))`` (identity when that is undefined: an axis along ±z);
- ``e = min(|effort| / limit, 1) + 0.05`` (``|effort| + 0.05`` without a limit: the URDF's ``<limit effort>``);
  radius ``r = 0.05 + e · scale · 0.5``;
- the arc: 30 points ``(r sin(2πi/32), r cos(2πi/32), 0)``, ``i = 0..29``, x negated for a negative effort, a
  line ``Width`` wide; the arrow: a head ``2 · width`` long at ``(0, r, 0)`` pointing along ``-x`` (a positive
  effort) or ``+x``; both in ``getRainbowColor(e)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from r2d2_viz.msgs.colormaps import rainbow
from r2d2_viz.msgs.geometry import quat_matrix
from r2d2_viz.msgs.shapes import Arrows, Decoded, LineStrips, MarkerOp

ARC_POINTS = 30
ARC_DIVISIONS = 32
WIDTH = 0.02
"""RViz's Width (m) and Scale defaults."""
SCALE = 1.0


@dataclass(frozen=True)
class EffortJoint:
    """What the Effort display needs of a URDF joint: its child link (the frame it is drawn in), axis and effort
    limit (0: none)."""

    name: str
    child: str
    axis: tuple[float, float, float]
    limit: float


def axis_rotation(axis: Sequence[float]) -> tuple[float, float, float, float]:
    """tf2's ``Quaternion(axis × z, axis.angle(z))`` (``xyzw``), identity where it is NaN (axis along ±z)."""
    a = np.asarray(axis, dtype=np.float64)
    n = np.cross(a, [0.0, 0.0, 1.0])
    length = float(np.linalg.norm(n))
    cos = float(np.dot(a, [0.0, 0.0, 1.0])) / (float(np.linalg.norm(a)) or 1.0)
    angle = math.acos(max(-1.0, min(1.0, cos)))
    if length == 0.0:
        return (0.0, 0.0, 0.0, 1.0)
    s = math.sin(angle / 2) / length
    return (float(n[0] * s), float(n[1] * s), float(n[2] * s), math.cos(angle / 2))


def effort_value(effort: float, limit: float) -> float:
    return min(abs(effort) / limit, 1.0) + 0.05 if limit != 0.0 else abs(effort) + 0.05


def joint_drawing(joint: EffortJoint, effort: float, stamp_ns: int, width: float, scale: float) -> Decoded:
    """One joint's arc and arrow head, in its child link's frame."""
    value = effort_value(effort, joint.limit)
    radius = 0.05 + value * scale * 0.5
    R = quat_matrix(axis_rotation(joint.axis))
    i = np.arange(ARC_POINTS, dtype=np.float64) * 2.0 * math.pi / ARC_DIVISIONS
    arc = np.stack([radius * np.sin(i), radius * np.cos(i), np.zeros(ARC_POINTS)], axis=1)
    if effort < 0:
        arc[:, 0] = -arc[:, 0]
    color = rainbow(np.array([value], dtype=np.float32))
    line = LineStrips(((arc @ R.T).astype(np.float32),), color, width / 2)
    head = R @ [0.0, radius, 0.0]
    direction = R @ ([-1.0, 0.0, 0.0] if effort > 0 else [1.0, 0.0, 0.0]) * (2.0 * width)
    arrow = Arrows(np.array([head], np.float32), np.array([direction], np.float32), color, width)
    return Decoded(joint.child, stamp_ns, (line, arrow))


def effort_ops(
    names: Sequence[str],
    efforts: Sequence[float],
    joints: Mapping[str, EffortJoint],
    stamp_ns: int,
    *,
    width: float = WIDTH,
    scale: float = SCALE,
) -> list[MarkerOp]:
    """A JointState's efforts (``names`` and ``efforts`` paired; none when the counts differ, as RViz refuses
    such a message) as one op per revolute joint the model has, keyed ``("effort", i)``: the joint's index in
    ``joints``, so each joint keeps its entity; a NaN effort is not drawn (RViz: "Invalid effort")."""
    if len(names) != len(efforts):
        return []
    index = {name: k for k, name in enumerate(joints)}
    ops = []
    for name, effort in zip(names, efforts, strict=True):
        joint = joints.get(name)
        if joint is None or not math.isfinite(effort):
            continue
        ops.append(MarkerOp("add", "effort", index[name], joint_drawing(joint, float(effort), stamp_ns, width, scale)))
    return ops
