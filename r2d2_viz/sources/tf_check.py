"""Does a bag's recorded /tf agree with the kinematics of its joint states? (robot_state_publisher was running
when it was recorded, so for the edges the URDF defines it should, to rounding.) Pure numpy; no rerun import."""

from __future__ import annotations

import numpy as np

from r2d2_viz.arrays import F64, I64
from r2d2_viz.kinematics.transforms import quat_multiply
from r2d2_viz.kinematics.tree import KinematicTree, moving_values, transforms_from_values
from r2d2_viz.sources.base import TfRecords

TOLERANCE_M = 1e-3
TOLERANCE_RAD = 1e-3


def urdf_edges(tree: KinematicTree) -> dict[tuple[str, str], tuple[str, int]]:
    """``(parent, child)`` of every joint that has a transform → (``moving`` or ``static``, its index)."""
    robot = tree.robot
    out: dict[tuple[str, str], tuple[str, int]] = {}
    for kind, names in (("moving", tree.moving), ("static", tree.static)):
        for i, name in enumerate(names):
            joint = robot.joint(name)
            out[joint.parent, joint.child] = (kind, i)
    return out


def disagreement(
    tree: KinematicTree, records: TfRecords, times_ns: I64, q: F64, *, joints_topic: str = "/joint_states"
) -> str | None:
    """The worst disagreement, in words, between ``records`` and the kinematics of the joint positions ``q``
    ``(T, A)`` held from ``times_ns`` ``(T,)`` on (the latest state at or before each record), if it exceeds
    1 mm or 1 mrad on some edge the URDF defines; else None. Records before the first state are not checked."""
    edges = urdf_edges(tree)
    rows = [i for i, edge in enumerate(zip(records.parents, records.children, strict=True)) if edge in edges]
    if not rows:
        return None
    static_t, static_q = tree.static_translation_quat()
    worst: tuple[float, float, str] = (0.0, 0.0, "")
    state = np.searchsorted(times_ns, records.times_ns[rows], side="right") - 1 if len(times_ns) else None
    translation = quat = None
    if state is not None:
        held = np.clip(state, 0, None)
        translation, quat = transforms_from_values(tree, moving_values(tree, q[held]))
    for k, i in enumerate(rows):
        kind, j = edges[records.parents[i], records.children[i]]
        if kind == "static":
            t_expected, q_expected = static_t[j], static_q[j]
        else:
            if state is None or state[k] < 0 or translation is None or quat is None:
                continue
            t_expected, q_expected = translation[k, j], quat[k, j]
        dt = float(np.linalg.norm(records.translation[i] - t_expected))
        dq = _angle(records.quat_xyzw[i], q_expected)
        if dt > worst[0] or dq > worst[1]:
            worst = (max(dt, worst[0]), max(dq, worst[1]), f"{records.parents[i]} → {records.children[i]}")
    if worst[0] <= TOLERANCE_M and worst[1] <= TOLERANCE_RAD:
        return None
    return (
        f"the recorded /tf disagrees with the kinematics of {joints_topic} by up to {worst[0] * 1e3:.3g} mm and "
        f"{worst[1] * 1e3:.3g} mrad (e.g. {worst[2]}); shown: the kinematics"
    )


def _angle(a: F64, b: F64) -> float:
    """Angle of the rotation between two ``xyzw`` quaternions."""
    a = np.asarray(a, dtype=np.float64) / np.linalg.norm(a)
    b = np.asarray(b, dtype=np.float64) / np.linalg.norm(b)
    inverse = b * np.array([-1.0, -1.0, -1.0, 1.0])
    w = abs(float(quat_multiply(inverse, a)[3]))
    return 2.0 * float(np.arccos(min(1.0, w)))
