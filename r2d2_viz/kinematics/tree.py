"""The pinned kinematics core: joint values → joint transforms and link poses, vectorised over samples.

It does what robot_state_publisher does with a URDF and a stream of joint states:

* fixed joints give constant transforms (``/tf_static``); a *planar* joint is treated as fixed;
* revolute, continuous and prismatic joints move about / along their axis, **without clamping**
  to the URDF limits; a mimic joint follows ``multiplier * master + offset``;
* a *floating* joint is skipped (no transform: its subtree is not connected to the root).

Inputs are ``q`` with shape ``(T, A)``: T samples × A actuated joints (``KinematicTree.actuated``).
Pure numpy; no rerun import.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import F64, I64
from r2d2_viz.errors import UrdfError
from r2d2_viz.kinematics.transforms import matrix_to_quat, quat_multiply
from r2d2_viz.robot.model import Robot

REVOLUTE, PRISMATIC = 0, 1


@dataclass(frozen=True, eq=False)
class KinematicTree:
    """A robot compiled into arrays. Links are indexed in ``robot.links`` order (root = 0)."""

    robot: Robot
    links: tuple[str, ...]
    actuated: tuple[str, ...]
    """Names of the joints whose values make up a row of ``q`` (movable, not mimic)."""
    moving: tuple[str, ...]
    """Joints that get a transform per sample: revolute, continuous, prismatic (mimics included)."""
    static: tuple[str, ...]
    """Joints whose transform never changes: fixed and planar."""
    warnings: tuple[str, ...]

    # per moving joint (M)
    moving_parent: I64
    moving_child: I64
    moving_kind: I64  # REVOLUTE or PRISMATIC
    moving_axis: F64  # (M, 3) unit axes in the joint frame
    moving_origin_t: F64  # (M, 3)
    moving_origin_R: F64  # (M, 3, 3)
    moving_origin_q: F64  # (M, 4) xyzw
    moving_source: I64  # (M,) column of q driving it
    moving_multiplier: F64  # (M,)
    moving_offset: F64  # (M,)

    # per static joint (S)
    static_parent: I64
    static_child: I64
    static_T: F64  # (S, 4, 4) T_parent_child

    @property
    def link_parent(self) -> I64:
        """Parent link of every link (indices into ``links``); -1 for the root and below a floating joint."""
        parent = np.full(len(self.links), -1, dtype=np.int64)
        parent[self.static_child] = self.static_parent
        parent[self.moving_child] = self.moving_parent
        return parent

    def static_translation_quat(self) -> tuple[F64, F64]:
        """Fixed-joint transforms as ``(translation (S, 3), quaternion xyzw (S, 4))``."""
        return self.static_T[:, :3, 3].copy(), matrix_to_quat(self.static_T[:, :3, :3])

    @property
    def limits(self) -> dict[str, tuple[float, float]]:
        """URDF ``[lower, upper]`` of each moving joint that has one (continuous joints have none)."""
        out: dict[str, tuple[float, float]] = {}
        for name in self.moving:
            joint = self.robot.joint(name)
            if joint.limit is not None and joint.type != "continuous":
                out[name] = (joint.limit.lower, joint.limit.upper)
        return out


def compile_tree(robot: Robot) -> KinematicTree:
    """Compile ``robot`` for :func:`joint_transforms` and :func:`link_positions`."""
    link_index = {link.name: i for i, link in enumerate(robot.links)}
    actuated = tuple(j.name for j in robot.actuated_joints)
    column = {name: i for i, name in enumerate(actuated)}
    by_name = {j.name: j for j in robot.joints}
    notes: list[str] = []

    moving = [j for j in robot.joints if j.movable]
    static = [j for j in robot.joints if j.type in ("fixed", "planar")]
    for j in robot.joints:
        if j.type == "planar":
            notes.append(f"{robot.source}: joint {j.name!r}: planar joints are not supported; treated as fixed")
        elif j.type == "floating":
            notes.append(
                f"{robot.source}: joint {j.name!r}: floating joints are not supported; skipped "
                f"(link {j.child!r} and below are not connected)"
            )

    sources, multipliers, offsets = [], [], []
    for j in moving:
        multiplier, offset, master = 1.0, 0.0, j
        seen = {j.name}
        while master.mimic is not None:  # follow mimic chains: a mimic of a mimic
            nxt = by_name.get(master.mimic.joint)
            if nxt is None or not nxt.movable:  # (a missing one is refused or dropped when the model is read)
                raise UrdfError(
                    f"{robot.source}: joint {master.name!r}: mimics {master.mimic.joint!r}, "
                    "which is not a revolute, continuous or prismatic joint"
                )
            if nxt.name in seen:  # urdf_check refuses mimic loops; never loop forever all the same
                raise RuntimeError(f"joint {j.name!r}: mimic joints form a cycle")
            seen.add(nxt.name)
            multiplier, offset = multiplier * master.mimic.multiplier, multiplier * master.mimic.offset + offset
            master = nxt
        sources.append(column[master.name])
        multipliers.append(multiplier)
        offsets.append(offset)

    def origin_R(joints: list) -> F64:  # type: ignore[type-arg]
        return np.array([j.T_parent_joint[:3, :3] for j in joints]).reshape(-1, 3, 3)

    moving_R = origin_R(moving)
    return KinematicTree(
        robot=robot,
        links=tuple(link.name for link in robot.links),
        actuated=actuated,
        moving=tuple(j.name for j in moving),
        static=tuple(j.name for j in static),
        warnings=tuple(notes),
        moving_parent=np.array([link_index[j.parent] for j in moving], dtype=np.int64),
        moving_child=np.array([link_index[j.child] for j in moving], dtype=np.int64),
        moving_kind=np.array([PRISMATIC if j.type == "prismatic" else REVOLUTE for j in moving], dtype=np.int64),
        moving_axis=np.array([j.axis for j in moving], dtype=np.float64).reshape(-1, 3),
        moving_origin_t=np.array([j.T_parent_joint[:3, 3] for j in moving]).reshape(-1, 3),
        moving_origin_R=moving_R,
        moving_origin_q=matrix_to_quat(moving_R).reshape(-1, 4),
        moving_source=np.array(sources, dtype=np.int64),
        moving_multiplier=np.array(multipliers, dtype=np.float64),
        moving_offset=np.array(offsets, dtype=np.float64),
        static_parent=np.array([link_index[j.parent] for j in static], dtype=np.int64),
        static_child=np.array([link_index[j.child] for j in static], dtype=np.int64),
        static_T=np.array([j.T_parent_joint for j in static]).reshape(-1, 4, 4),
    )


def _as_samples(tree: KinematicTree, q: npt.ArrayLike) -> F64:
    q = np.asarray(q, dtype=np.float64)
    if q.ndim == 1:
        q = q[None, :]
    if q.ndim != 2 or q.shape[1] != len(tree.actuated):
        raise ValueError(f"q must have shape (T, {len(tree.actuated)}) for joints {tree.actuated}, got {q.shape}")
    return q


def moving_values(tree: KinematicTree, q: npt.ArrayLike) -> F64:
    """Values ``(T, M)`` of every moving joint, mimics resolved."""
    q = _as_samples(tree, q)
    return q[:, tree.moving_source] * tree.moving_multiplier + tree.moving_offset


def joint_transforms(tree: KinematicTree, q: npt.ArrayLike) -> tuple[F64, F64]:
    """``T_parent_child`` of every moving joint as ``(translation (T, M, 3), quaternion xyzw (T, M, 4))``."""
    return transforms_from_values(tree, moving_values(tree, q))


def transforms_from_values(tree: KinematicTree, values: F64) -> tuple[F64, F64]:
    """:func:`joint_transforms` from the values ``(T, M)`` of the moving joints (see :func:`moving_values`), as
    ``(translation (T, M, 3), quaternion xyzw (T, M, 4))`` (see :func:`write_transforms`)."""
    n_samples, n_moving = len(values), len(tree.moving)
    translation, quat = np.empty((n_samples, n_moving, 3)), np.empty((n_samples, n_moving, 4))
    write_transforms(tree, values, translation, quat)
    return translation, quat


def write_transforms(
    tree: KinematicTree, values: F64, translation: npt.NDArray[np.floating], quat: npt.NDArray[np.floating]
) -> None:
    """``T_parent_child`` of the moving joints for their values ``(T, M)``, written into ``translation[:, :M]`` and
    ``quat[:, :M]`` (arrays ``(T, ≥M, 3)`` and ``(T, ≥M, 4)`` xyzw, of any float type: computed in float64,
    cast as they are written).

    Per joint, ``origin ⊗ rot(axis, θ) = sin(θ/2) · (origin ⊗ (axis, 0)) + cos(θ/2) · origin`` and a prismatic
    shift is ``t_origin + d · (R_origin · axis)``; what does not move with the samples (a revolute joint's
    translation, a prismatic joint's rotation: ``θ = 0``, ``d = 0`` in the same formulas) is computed once per
    joint. The per-sample arithmetic (one sin, one cos and a few multiply-adds) runs over each kind's joints with
    the samples contiguous (numpy is slow on many short rows), then lands transposed in the outputs.
    """
    f = _factors(tree)
    by_joint = np.asarray(values, dtype=np.float64).T  # (M, T), a view
    if f.n_revolute:
        half = by_joint[f.revolute] * 0.5  # (R, T), contiguous
        sin, cos = np.sin(half), np.cos(half)
        part, scratch = np.empty_like(half), np.empty_like(half)
        for k in range(4):
            np.multiply(sin, f.axis_q[f.revolute, k, None], out=part)
            np.multiply(cos, f.origin_q[f.revolute, k, None], out=scratch)
            part += scratch
            quat[:, f.revolute, k] = part.T
        translation[:, f.revolute] = f.still_t[f.revolute]
    if f.n_prismatic:
        shift = by_joint[f.prismatic]  # (P, T)
        part = np.empty_like(shift)
        for k in range(3):
            np.multiply(shift, f.direction[f.prismatic, k, None], out=part)
            part += tree.moving_origin_t[f.prismatic, k, None]
            translation[:, f.prismatic, k] = part.T
        quat[:, f.prismatic] = f.still_q[f.prismatic]


@dataclass(frozen=True)
class _Factors:
    """Per-joint factors of :func:`write_transforms`, computed once per tree."""

    revolute: slice | I64
    prismatic: slice | I64
    n_revolute: int
    n_prismatic: int
    origin_q: F64  # (M, 4)
    axis_q: F64  # (M, 4) origin ⊗ (axis, 0)
    direction: F64  # (M, 3) R_origin · axis
    still_t: F64  # (M, 3) 0 · direction + t_origin: a revolute joint's translation
    still_q: F64  # (M, 4) sin(0) · axis_q + cos(0) · origin_q: a prismatic joint's rotation


@lru_cache(maxsize=8)
def _factors(tree: KinematicTree) -> _Factors:
    n_moving = len(tree.moving)
    origin_q = tree.moving_origin_q
    axis_q = quat_multiply(origin_q, np.concatenate([tree.moving_axis, np.zeros((n_moving, 1))], axis=-1))
    direction = np.einsum("mij,mj->mi", tree.moving_origin_R, tree.moving_axis)
    zero = np.zeros((n_moving, 1))
    revolute = np.flatnonzero(tree.moving_kind == REVOLUTE)
    prismatic = np.flatnonzero(tree.moving_kind != REVOLUTE)
    return _Factors(
        revolute=_as_slice(revolute),
        prismatic=_as_slice(prismatic),
        n_revolute=len(revolute),
        n_prismatic=len(prismatic),
        origin_q=origin_q,
        axis_q=axis_q,
        direction=direction,
        still_t=zero * direction + tree.moving_origin_t,
        still_q=np.sin(zero) * axis_q + np.cos(zero) * origin_q,
    )


def _as_slice(index: I64) -> slice | I64:
    """A run of consecutive indices as a slice (numpy then writes through a view, not a gather)."""
    if len(index) and index[-1] - index[0] == len(index) - 1:
        return slice(int(index[0]), int(index[-1]) + 1)
    return index


def link_positions(
    tree: KinematicTree,
    translation: F64,
    quat: F64,
    links: Sequence[int],
    *,
    root_pose: tuple[F64, F64] | None = None,
) -> dict[int, F64]:
    """Origins ``(T, 3)`` of ``links`` (indices into ``tree.links``) in the fixed frame, from the moving
    joints' transforms already computed by :func:`transforms_from_values`: only the links asked for and
    their ancestors are composed, as rotation and translation (no 4×4 matrices for the whole tree), one
    depth of the tree at a time (a few numpy calls per depth, however many links share it).
    Links below a floating joint are NaN. ``root_pose``: the root's pose in the fixed frame per sample,
    ``(translation (T, 3), quaternion xyzw (T, 4))``; None: the root is the fixed frame."""
    n_samples = translation.shape[0]
    plan = _composition_plan(tree, tuple(int(link) for link in links))
    # samples last ("structure of arrays"): every matrix entry is one contiguous run of samples, so composing is
    # 27 + 9 multiply-adds over long vectors instead of many small 3×3 products
    R = np.empty((3, 3, len(plan.links), n_samples))
    t = np.empty((3, len(plan.links), n_samples))
    if root_pose is None:
        R[:, :, 0], t[:, 0] = np.eye(3)[:, :, None], 0.0
    else:
        t[:, 0], R[:, :, 0] = root_pose[0].T, _matrices_samples_last(root_pose[1])
    for level in plan.levels:
        for g in level:
            R_parent = R[:, :, g.parent]  # (3, 3, [G,] T): a view when the group is a single link
            if g.moving:
                t_local = np.swapaxes(np.moveaxis(translation[:, g.index], -1, 0), 1, -1)  # (3, [G,] T)
            else:
                t_local = np.moveaxis(tree.static_T[g.index, :3, 3], -1, 0)[..., None]  # (3, [G,] 1)
            t[:, g.child] = t[:, g.parent] + _rotate(R_parent, t_local)
            if g.has_children:  # a rotation is only needed to go further down
                if g.moving:
                    R_local = _matrices_samples_last(quat[:, g.index])
                else:
                    R_local = np.moveaxis(tree.static_T[g.index, :3, :3], (-2, -1), (0, 1))[..., None]
                R[:, :, g.child] = _compose(R_parent, R_local)
    out = {}
    for link in links:
        k = plan.compact.get(int(link))
        out[link] = t[:, k].T if k is not None else np.full((n_samples, 3), np.nan)
    return out


def _rotate(R: F64, v: F64) -> F64:
    """``R · v`` for matrices ``(3, 3, …)`` and vectors ``(3, …)``, samples last."""
    return np.stack([R[i, 0] * v[0] + R[i, 1] * v[1] + R[i, 2] * v[2] for i in range(3)])


def _compose(A: F64, B: F64) -> F64:
    """``A · B`` for matrices ``(3, 3, …)``, samples last."""
    return np.stack([_rotate(A, B[:, j]) for j in range(3)], axis=1)


def _matrices_samples_last(quat_xyzw: F64) -> F64:
    """Rotation matrices ``(3, 3, [G,] T)`` of quaternions ``(T, [G,] 4)`` (xyzw), as :func:`quat_to_matrix`."""
    unit = quat_xyzw / np.linalg.norm(quat_xyzw, axis=-1, keepdims=True)
    x, y, z, w = np.swapaxes(np.moveaxis(unit, -1, 0), 1, -1)  # each ([G,] T)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)]),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)]),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]),
        ]
    )


@dataclass(frozen=True)
class _Group:
    """Links of one depth whose transforms are all moving or all static, composed in one step."""

    child: int | I64
    """Positions in the plan's compact order: an int for a single link (numpy then indexes a view)."""
    parent: int | I64
    moving: bool
    index: int | I64
    """Columns of the moving joints' transforms, or rows of ``static_T``."""
    has_children: bool
    """Whether any of these links is the parent of a link in the plan (else its rotation is not needed)."""


@dataclass(frozen=True)
class _Plan:
    links: tuple[int, ...]
    """The links composed (root first), in compact order; ``compact`` maps a link to its position."""
    compact: dict[int, int]
    levels: tuple[tuple[_Group, ...], ...]
    """Per depth below the root, its groups."""


@lru_cache(maxsize=8)
def _composition_plan(tree: KinematicTree, links: tuple[int, ...]) -> _Plan:
    """Which links to compose, grouped by depth: linear in the number of links (iterative walks)."""
    parent = tree.link_parent
    moving_of = dict(zip(tree.moving_child.tolist(), range(len(tree.moving)), strict=True))
    static_of = dict(zip(tree.static_child.tolist(), range(len(tree.static)), strict=True))
    depth: dict[int, int] = {0: 0}  # links connected to the root; links below a floating joint stay out
    cut: set[int] = set()
    for link in links:
        path = []
        while link not in depth and link not in cut:
            path.append(link)
            link = int(parent[link])
            if link < 0:
                break
        base = depth.get(link) if link >= 0 else None
        for k, c in enumerate(reversed(path)):
            if base is None:
                cut.add(c)
            else:
                depth[c] = base + k + 1
    order = sorted(depth, key=depth.__getitem__)  # root first, then by depth
    compact = {link: k for k, link in enumerate(order)}
    parents = {int(parent[link]) for link in order[1:]}
    by_depth: dict[int, list[int]] = {}
    for link in order[1:]:
        by_depth.setdefault(depth[link], []).append(link)

    def indices(values: list[int]) -> int | I64:
        return values[0] if len(values) == 1 else np.array(values, dtype=np.int64)

    levels = []
    for d in sorted(by_depth):
        groups = []
        for moving, table in ((True, moving_of), (False, static_of)):
            members = [c for c in by_depth[d] if c in table]
            if members:
                groups.append(
                    _Group(
                        child=indices([compact[c] for c in members]),
                        parent=indices([compact[int(parent[c])] for c in members]),
                        moving=moving,
                        index=indices([table[c] for c in members]),
                        has_children=any(c in parents for c in members),
                    )
                )
        levels.append(tuple(groups))
    return _Plan(tuple(order), compact, tuple(levels))
