"""/tf rows: one per moving joint, then one per frame track; the moving arrows' ends against whole-tree FK."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
from fk import link_poses

from r2d2_viz.kinematics.tree import compile_tree, moving_values
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.robot.synth import random_urdf
from r2d2_viz.sources.base import FrameTrack
from r2d2_viz.viewer.tf_rows import TfRows


def test_rows_names_and_moving_arrows(tmp_path) -> None:
    path = tmp_path / "r.urdf"
    path.write_text(random_urdf(25, seed=11, joint_types=("fixed", "revolute", "prismatic", "continuous")))
    tree = compile_tree(load_urdf(path))
    robot = tree.robot
    rows = TfRows(tree, tracks=(("odom", robot.root),), fixed_frame="odom")
    moving = [robot.joint(name) for name in tree.moving]
    assert rows.children == [*(j.child for j in moving), robot.root]
    assert rows.parents == [*(j.parent for j in moving), "odom"]
    n = 7
    rng = np.random.default_rng(2)
    q = rng.uniform(-1, 1, (n, len(tree.actuated)))
    t_root = rng.uniform(-1, 1, (n, 3))
    yaw = rng.uniform(-3, 3, n)
    quat = np.stack([np.zeros(n), np.zeros(n), np.sin(yaw / 2), np.cos(yaw / 2)], axis=1)
    columns = dict(rows.encode(moving_values(tree, q), (FrameTrack("odom", robot.root, t_root, quat),)))
    by_name = {str(d).split(":")[-1]: a for d, a in columns.items()}
    assert by_name["child_frame"].flatten().to_pylist() == rows.children * n
    # arrows on each sample's first row: from each prismatic child's origin to its parent's, and root → odom
    origins = by_name["origins"]
    assert origins.null_count == n * (rows.rows - 1)
    first = pa.array([origins[i * rows.rows].as_py() for i in range(n)]).to_pylist()
    T_root = np.zeros((n, 4, 4))
    T_root[:, 3, 3] = 1
    c, s = np.cos(yaw), np.sin(yaw)
    T_root[:, 0, 0], T_root[:, 0, 1], T_root[:, 1, 0], T_root[:, 1, 1], T_root[:, 2, 2] = c, -s, s, c, 1
    T_root[:, :3, 3] = t_root
    poses = link_poses(tree, q, T_fixed_root=T_root)
    index = {name: i for i, name in enumerate(tree.links)}
    ends = [j for j in moving if j.type == "prismatic"]
    for k in range(n):
        expected = [poses[k, index[j.child], :3, 3] for j in ends] + [t_root[k]]
        assert np.allclose(np.array(first[k]), expected, atol=1e-5)
