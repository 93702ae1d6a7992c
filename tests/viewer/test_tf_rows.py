"""/tf rows: one per moving joint, then one per frame track; the moving arrows' ends against whole-tree FK."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from fk import link_poses

from r2d2_viz.kinematics.tree import compile_tree, moving_values, transforms_from_values
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.robot.synth import random_urdf
from r2d2_viz.sources.base import FrameTrack
from r2d2_viz.viewer.columns import first_of_every
from r2d2_viz.viewer.scene import ARROW_COLOR
from r2d2_viz.viewer.tf_rows import TfRows, arrow_columns


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
        parents = [poses[k, index[j.parent], :3, 3] for j in ends] + [np.zeros(3)]  # the root's parent: odom
        vectors = by_name["vectors"][k * rows.rows].as_py()
        assert np.allclose(np.array(vectors), np.array(parents) - expected, atol=1e-5)
    # the arrow columns are built from buffers: the very Arrow arrays (types, nulls, colours) Rerun's builder makes
    # of the same float32 origins and vectors, partitioned per sample and spread over each sample's rows
    k = len(ends) + 1
    on_first = [i * rows.rows for i in range(n)]
    built = rr.Arrows3D.columns(
        origins=np.array([origins[i].as_py() for i in on_first], dtype=np.float32).reshape(-1, 3),
        vectors=np.array([by_name["vectors"][i].as_py() for i in on_first], dtype=np.float32).reshape(-1, 3),
        colors=np.broadcast_to(np.array(ARROW_COLOR, dtype=np.uint8), (n * k, 3)),
    ).partition(np.full(n, k))
    arrow_columns = {str(d): (d, a) for d, a in columns.items() if str(d).startswith("Arrows3D")}
    assert len(arrow_columns) == 3
    for column in built:
        d, a = arrow_columns[str(column.component_descriptor())]
        assert d == column.component_descriptor()
        assert a.equals(first_of_every(column.as_arrow_array(), rows.rows)), d


@pytest.mark.parametrize("root_track", [True, False])
def test_columns_are_what_rerun_builds_from_the_float64_transforms(tmp_path, root_track: bool) -> None:
    """The columns are built from buffers (issue 38): they must equal, descriptor and Arrow array alike, what
    ``rr.Transform3D.columns`` builds from the float64 transforms (Rerun casts them to float32) — a revolute-only
    tree without a root track takes the float32 path, the others the float64 one (their arrows need it)."""
    path = tmp_path / "r.urdf"
    types = ("fixed", "revolute", "prismatic", "continuous") if root_track else ("fixed", "revolute", "continuous")
    path.write_text(random_urdf(20, seed=5, joint_types=types))
    tree = compile_tree(load_urdf(path))
    robot = tree.robot
    edges = (("odom", robot.root), ("map", "odom")) if root_track else (("map", "odom"),)
    rows = TfRows(tree, tracks=edges, fixed_frame="odom")
    n = 50
    rng = np.random.default_rng(3)
    values = moving_values(tree, rng.uniform(-4, 4, (n, len(tree.actuated))))
    t_track = rng.uniform(-1, 1, (n, 3))
    t_track[7] = 1e300  # beyond float32: +inf
    quat = rng.normal(size=(n, 4))
    tracks = tuple(FrameTrack(p, c, t_track * (k + 1), quat) for k, (p, c) in enumerate(edges))
    for _ in range(2):  # the frame names are reused for a second chunk of the same length
        got = rows.encode(values, tracks)
        translation, q = transforms_from_values(tree, values)
        translation = np.concatenate([translation, *(t.translation[:, None] for t in tracks)], axis=1)
        q = np.concatenate([q, *(t.quat_xyzw[:, None] for t in tracks)], axis=1)
        with np.errstate(over="ignore"):
            expected = rr.Transform3D.columns(
                translation=translation.reshape(-1, 3).astype(np.float32),
                quaternion=q.reshape(-1, 4),
                parent_frame=rows.parents * n,
                child_frame=rows.children * n,
            )
        by_descriptor = {str(d): (d, a) for d, a in got}
        for column in expected:
            d, a = by_descriptor[str(column.component_descriptor())]
            assert d == column.component_descriptor()
            assert a.equals(column.as_arrow_array()), d
        assert np.isinf(by_descriptor["Transform3D:translation"][1].flatten().flatten().to_numpy()).any()


def test_arrow_columns_without_colour_are_what_rerun_builds() -> None:
    """A recorded edge's arrows (``viewer/tf_recorded.py``): one arrow a row, no colour column — the very columns of
    ``rr.Arrows3D.columns``."""
    rng = np.random.default_rng(4)
    origins = rng.normal(size=(9, 3)).astype(np.float32)
    got = dict(arrow_columns(origins, -origins))
    expected = rr.Arrows3D.columns(origins=origins, vectors=-origins)
    assert len(got) == 2
    for column in expected:
        by_descriptor = {str(d): (d, a) for d, a in got.items()}
        d, a = by_descriptor[str(column.component_descriptor())]
        assert d == column.component_descriptor() and a.equals(column.as_arrow_array()), d
