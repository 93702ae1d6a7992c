"""Whole-tree forward kinematics with 4×4 matrices, link by link: the plain form the tests compare
:func:`r2d2_viz.kinematics.tree.link_positions` against (test-only; the app composes only what it draws)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import F64
from r2d2_viz.kinematics.transforms import quat_to_matrix
from r2d2_viz.kinematics.tree import KinematicTree, joint_transforms


def link_poses(tree: KinematicTree, q: npt.ArrayLike, *, T_fixed_root: npt.ArrayLike | None = None) -> F64:
    """Pose of every link in the fixed frame, ``(T, L, 4, 4)``; the root's pose is ``T_fixed_root``
    (identity by default). Links below a floating joint are NaN."""
    translation, quat = joint_transforms(tree, q)
    n_frames = translation.shape[0]
    T_joint = np.zeros((n_frames, len(tree.moving), 4, 4))
    T_joint[..., :3, :3] = quat_to_matrix(quat)
    T_joint[..., :3, 3] = translation
    T_joint[..., 3, 3] = 1.0

    # local transform per link, then compose in link order (parents come first).
    n_links = len(tree.links)
    local = np.full((n_frames, n_links, 4, 4), np.nan)
    local[:, tree.static_child] = tree.static_T
    local[:, tree.moving_child] = T_joint
    parent = tree.link_parent

    poses = np.empty((n_frames, n_links, 4, 4))
    poses[:, 0] = np.eye(4) if T_fixed_root is None else np.asarray(T_fixed_root, dtype=np.float64)
    for i in range(1, n_links):
        p = parent[i]
        poses[:, i] = np.nan if p < 0 else poses[:, p] @ local[:, i]
    return poses
