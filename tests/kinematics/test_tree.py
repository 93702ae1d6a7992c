"""The kinematics core, pinned three ways:

1. golden poses of the R2D2 worked out by hand (derivations in the comments);
2. yourdfpy's forward kinematics on 1,000 random configurations (R2D2 and a random tree);
3. Rerun's own URDF joint maths (``rr.urdf.UrdfTree``, ``clamp=False``) on the same configurations,
   including every joint type (floating and planar: see the module docstring of kinematics.py).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import rerun as rr
import yourdfpy
from fk import link_poses
from reference import quat_xyzw_to_matrix

from r2d2_viz.kinematics.transforms import matrix_to_quat, quat_to_matrix
from r2d2_viz.kinematics.tree import compile_tree, joint_transforms, moving_values
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.robot.synth import random_urdf

TOL = 1e-9
N_CONFIGS = 1000
S3 = math.sqrt(3) / 2  # cos 30°


@pytest.fixture(scope="module")
def r2d2(tutorial_urdf: Path):
    return compile_tree(load_urdf(tutorial_urdf))


def _q(tree, **values: float) -> np.ndarray:
    return np.array([[values.get(name, 0.0) for name in tree.actuated]])


def test_r2d2_golden_poses_by_hand(r2d2) -> None:
    # odom → axis as state_publisher puts it at angle 0: translation (2, 0, 0.7), yaw 90°.
    Rz90 = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    T_odom_axis = np.eye(4)
    T_odom_axis[:3, :3] = Rz90
    T_odom_axis[:3, 3] = [2, 0, 0.7]
    q = _q(r2d2, tilt=-math.pi / 6, swivel=math.pi / 2, periscope=0.1)
    P = dict(zip(r2d2.links, link_poses(r2d2, q, T_fixed_root=T_odom_axis)[0], strict=True))

    # leg1: axis + Rz90·(0, .3, 0) = (2 − .3, 0, .7); leg2 mirrored.
    assert np.allclose(P["leg1"][:3, 3], [1.7, 0, 0.7], atol=TOL)
    assert np.allclose(P["leg2"][:3, 3], [2.3, 0, 0.7], atol=TOL)
    # body: tilt −30° about y: R = Rz90·Ry(−30°) = [[0,−1,0],[cos30,0,−.5],[.5,0,cos30]].
    assert np.allclose(P["body"][:3, :3], [[0, -1, 0], [S3, 0, -0.5], [0.5, 0, S3]], atol=TOL)
    assert np.allclose(P["body"][:3, 3], [2, 0, 0.7], atol=TOL)
    # head: body + R_body·(0, 0, .1) = (2, −.05, .7 + .1·cos30).
    assert np.allclose(P["head"][:3, 3], [2, -0.05, 0.7 + 0.1 * S3], atol=TOL)
    # rod: head + R_body·Rz(90°)·(.12, 0, .15 + .1) → Rz90: (0, .12, .25) → Ry(−30°): (−.125, .12, .25·cos30)
    #      → Rz90: (−.12, −.125, .25·cos30).
    assert np.allclose(P["rod"][:3, 3], [2 - 0.12, -0.05 - 0.125, 0.7 + 0.1 * S3 + 0.25 * S3], atol=TOL)
    # rod's orientation: Rz90·Ry(−30°)·Rz90 = [[−1,0,0],[0,−cos30,−.5],[0,.5,−... no: compute columns:
    # Rz90·Ry(−30°) = B (above); B·Rz90 = [B[:,1], −B[:,0], B[:,2]].
    B = np.array([[0, -1, 0], [S3, 0, -0.5], [0.5, 0, S3]])
    assert np.allclose(P["rod"][:3, :3], np.column_stack([B[:, 1], -B[:, 0], B[:, 2]]), atol=TOL)
    assert np.allclose(P["box"], P["rod"], atol=TOL)  # boxconnect: fixed, zero origin


def test_r2d2_at_zero_is_the_urdf_origins(r2d2) -> None:
    P = dict(zip(r2d2.links, link_poses(r2d2, _q(r2d2))[0], strict=True))
    expected = {
        "axis": (0, 0, 0),
        "leg1": (0, 0.3, 0),
        "leg2": (0, -0.3, 0),
        "body": (0, 0, 0),
        "head": (0, 0, 0.1),
        "rod": (0.12, 0, 0.25),
        "box": (0.12, 0, 0.25),
    }
    for link, xyz in expected.items():
        assert np.allclose(P[link][:3, 3], xyz, atol=TOL), link
        assert np.allclose(P[link][:3, :3], np.eye(3), atol=TOL), link


def test_values_outside_the_limits_are_not_clamped(r2d2) -> None:
    inside = link_poses(r2d2, _q(r2d2, periscope=0.0))[0]
    outside = link_poses(r2d2, _q(r2d2, periscope=0.2))[0]  # limit [−0.5, 0]
    rod = r2d2.links.index("rod")
    assert outside[rod][2, 3] - inside[rod][2, 3] == pytest.approx(0.2, abs=TOL)


def _random_configs(tree, n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-3.0, 3.0, size=(n, len(tree.actuated)))


def _yourdfpy_poses(urdf_path: Path, tree, q: np.ndarray) -> np.ndarray:
    urdf = yourdfpy.URDF.load(str(urdf_path), load_meshes=False)
    out = np.empty((len(q), len(tree.links), 4, 4))
    for k, row in enumerate(q):
        urdf.update_cfg(dict(zip(tree.actuated, row, strict=True)))
        for i, link in enumerate(tree.links):
            out[k, i] = urdf.get_transform(frame_to=link, frame_from=tree.links[0])
    return out


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    return path


@pytest.mark.parametrize("robot", ["r2d2", "random_tree"])
def test_matches_yourdfpy_on_1000_random_configurations(robot: str, tutorial_urdf: Path, tmp_path: Path) -> None:
    if robot == "r2d2":
        path = tutorial_urdf
    else:  # yourdfpy has no floating/planar semantics to compare: movable, fixed and mimic joints only
        path = _write(
            tmp_path,
            random_urdf(40, seed=7, joint_types=("fixed", "revolute", "continuous", "prismatic"), mimic_fraction=0.3),
        )
    tree = compile_tree(load_urdf(path))
    q = _random_configs(tree, N_CONFIGS, seed=1)
    ours = link_poses(tree, q)
    theirs = _yourdfpy_poses(path, tree, q)
    assert np.abs(ours - theirs).max() < TOL


def _rerun_poses(urdf_path: Path, tree, q: np.ndarray) -> np.ndarray:
    """Compose Rerun's per-joint transforms (its own URDF parser and joint maths) along the tree."""
    urdf = rr.urdf.UrdfTree.from_file_path(urdf_path)
    joints = {j.name: j for j in urdf.joints()}
    robot = tree.robot
    n = len(q)
    poses = {robot.root: np.broadcast_to(np.eye(4), (n, 4, 4))}
    value_of = {name: q[:, i] for i, name in enumerate(tree.actuated)}
    for joint in robot.joints:  # parents first
        rj = joints[joint.name]
        if rj.joint_type.lower() == "floating":
            continue  # skipped like robot_state_publisher: the subtree is not connected
        if rj.joint_type.lower() in ("fixed", "planar"):
            T = np.eye(4)
            T[:3, :3] = _rpy(rj.origin_rpy)
            T[:3, 3] = rj.origin_xyz
            local = np.broadcast_to(T, (n, 4, 4))
        else:
            mimic = rj.mimic
            values = value_of[joint.name] if mimic is None else mimic.multiplier * value_of[mimic.joint] + mimic.offset
            value_of[joint.name] = values
            # UrdfJoint.compute_transform_columns (public API): Transform3D columns, read back from Arrow
            columns = rj.compute_transform_columns([float(v) for v in values], clamp=False)
            raw = {str(c.component_descriptor()).split(":")[-1]: c.as_arrow_array() for c in columns}
            raw = {k: np.asarray(raw[k].flatten().flatten()) for k in ("translation", "quaternion")}
            local = np.zeros((n, 4, 4))
            local[:, :3, :3] = quat_xyzw_to_matrix(raw["quaternion"].reshape(-1, 4))
            local[:, :3, 3] = raw["translation"].reshape(-1, 3)
            local[:, 3, 3] = 1.0
        if joint.parent in poses:
            poses[joint.child] = poses[joint.parent] @ local
    return np.stack([poses.get(link, np.full((n, 4, 4), np.nan)) for link in tree.links], axis=1)


def _rpy(rpy) -> np.ndarray:
    r, p, y = rpy
    Rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    Ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    Rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


@pytest.mark.parametrize("robot", ["r2d2", "random_tree_all_joint_types"])
def test_matches_rerun_urdf_joint_transforms_on_1000_random_configurations(
    robot: str, tutorial_urdf: Path, tmp_path: Path
) -> None:
    path = tutorial_urdf if robot == "r2d2" else _write(tmp_path, random_urdf(40, seed=11, mimic_fraction=0.3))
    tree = compile_tree(load_urdf(path))
    if robot != "r2d2":
        assert {j.type for j in tree.robot.joints} == {
            "fixed",
            "revolute",
            "continuous",
            "prismatic",
            "floating",
            "planar",
        }
        assert any(j.mimic for j in tree.robot.joints)
    q = _random_configs(tree, N_CONFIGS, seed=2)
    ours = link_poses(tree, q)
    theirs = _rerun_poses(path, tree, q)
    connected = ~np.isnan(theirs[0, :, 0, 0])
    assert np.array_equal(connected, ~np.isnan(ours[0, :, 0, 0]))  # same links cut off below floating joints
    # Rerun's joint maths is float32 (it returns 0.12 as 0.11999999731779099), ours float64: 1e-9 is out of
    # reach for it, so its rounding sets the tolerance here; the yourdfpy cross-check holds 1e-9.
    assert np.abs(ours[:, connected] - theirs[:, connected]).max() < 1e-5


def test_floating_and_planar_joints_warn(tmp_path: Path) -> None:
    tree = compile_tree(load_urdf(_write(tmp_path, random_urdf(30, seed=11))))
    text = "\n".join(tree.warnings)
    assert "floating joints are not supported; skipped" in text
    assert "planar joints are not supported; treated as fixed" in text


def test_mimic_follows_multiplier_times_master_plus_offset(tmp_path: Path) -> None:
    urdf = """<robot name="m"><link name="a"/><link name="b"/><link name="c"/>
    <joint name="master" type="prismatic"><parent link="a"/><child link="b"/><axis xyz="1 0 0"/>
      <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="follower" type="prismatic"><parent link="a"/><child link="c"/><axis xyz="0 1 0"/>
      <limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="master" multiplier="-2" offset="0.5"/></joint>
    </robot>"""
    tree = compile_tree(load_urdf(_write(tmp_path, urdf)))
    assert tree.actuated == ("master",)
    P = link_poses(tree, [[0.25]])[0]
    assert np.allclose(P[tree.links.index("c")][:3, 3], [0, -2 * 0.25 + 0.5, 0], atol=TOL)


def test_frames_are_independent_vectorised_equals_one_by_one(r2d2) -> None:
    q = _random_configs(r2d2, 50, seed=3)
    batch = link_poses(r2d2, q)
    single = np.stack([link_poses(r2d2, row)[0] for row in q])
    assert np.abs(batch - single).max() < 1e-12
    t, quat = joint_transforms(r2d2, q)
    assert t.shape == (50, 3, 3) and quat.shape == (50, 3, 4)
    assert np.allclose(np.linalg.norm(quat, axis=-1), 1, atol=1e-12)


def test_a_chain_of_3000_links_needs_no_recursion(tmp_path: Path) -> None:
    tree = compile_tree(
        load_urdf(
            _write(tmp_path, random_urdf(3000, seed=5, chain=True, visuals=False, joint_types=("revolute", "fixed")))
        )
    )
    poses = link_poses(tree, np.zeros((2, len(tree.actuated))))
    assert poses.shape == (2, 3000, 4, 4) and np.isfinite(poses).all()


def test_quaternion_conversions_against_known_rotations() -> None:
    # 90° about z: (0, 0, sin 45°, cos 45°); 180° about x: (1, 0, 0, 0) — the case Shepperd's method exists for.
    Rz90 = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    Rx180 = np.diag([1.0, -1.0, -1.0])
    assert np.allclose(matrix_to_quat(Rz90), [0, 0, math.sqrt(0.5), math.sqrt(0.5)], atol=TOL)
    assert np.allclose(np.abs(matrix_to_quat(Rx180)), [1, 0, 0, 0], atol=TOL)
    R = np.stack([_rpy(v) for v in np.random.default_rng(0).uniform(-math.pi, math.pi, (200, 3))])
    assert np.allclose(quat_to_matrix(matrix_to_quat(R)), R, atol=1e-12)


def test_link_positions_of_a_few_links_match_the_full_poses(tmp_path: Path) -> None:
    from r2d2_viz.kinematics.tree import link_positions, transforms_from_values

    tree = compile_tree(load_urdf(_write(tmp_path, random_urdf(30, seed=11, mimic_fraction=0.3))))
    q = _random_configs(tree, 20, seed=4)
    T_root = np.broadcast_to(np.eye(4), (20, 4, 4)).copy()
    T_root[:, :3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]  # 90° about z, by hand: xyzw (0, 0, sin 45°, cos 45°)
    T_root[:, :3, 3] = [1.0, -2.0, 0.5]
    full = link_poses(tree, q, T_fixed_root=T_root)
    translation, quat = transforms_from_values(tree, moving_values(tree, q))
    links = [3, 17, 29, 0]
    root_pose = (np.tile([1.0, -2.0, 0.5], (20, 1)), np.tile([0, 0, math.sqrt(0.5), math.sqrt(0.5)], (20, 1)))
    got = link_positions(tree, translation, quat, links, root_pose=root_pose)
    for link in links:
        assert np.allclose(got[link], full[:, link, :3, 3], atol=1e-12, equal_nan=True), link
    assert any(np.isnan(full[0, i, 0, 3]) for i in range(30))  # the tree has a floating joint: NaN subtrees


@pytest.mark.parametrize("chain", [True, False], ids=["chain", "tree"])
def test_link_positions_of_every_link_match_the_full_poses(tmp_path: Path, chain: bool) -> None:
    # Deep chains and wide trees: positions are composed depth by depth, many links at once; link_poses
    # (checked against yourdfpy above) composes link by link.
    from r2d2_viz.kinematics.tree import link_positions, transforms_from_values

    tree = compile_tree(load_urdf(_write(tmp_path, random_urdf(300, seed=2, chain=chain, mimic_fraction=0.2))))
    q = _random_configs(tree, 5, seed=9)
    full = link_poses(tree, q)
    translation, quat = transforms_from_values(tree, moving_values(tree, q))
    every = list(range(len(tree.links)))
    got = link_positions(tree, translation, quat, every)
    assert np.allclose(np.stack([got[i] for i in every], axis=1), full[..., :3, 3], atol=1e-9, equal_nan=True)


def test_written_transforms_are_the_float64_ones_cast_and_leave_the_other_rows(tmp_path: Path) -> None:
    """``write_transforms`` into float32 rows of a wider array (the /tf columns, issue 38): the float64
    transforms (checked against yourdfpy above) cast to float32, the rows beyond the moving joints untouched."""
    from r2d2_viz.kinematics.tree import transforms_from_values, write_transforms

    path = tmp_path / "r.urdf"
    path.write_text(random_urdf(30, seed=4, joint_types=("fixed", "revolute", "prismatic", "continuous")))
    tree = compile_tree(load_urdf(path))
    q = np.random.default_rng(4).uniform(-3, 3, (40, len(tree.actuated)))
    values = moving_values(tree, q)
    m = len(tree.moving)
    translation = np.full((40, m + 2, 3), 7.0, dtype=np.float32)
    quat = np.full((40, m + 2, 4), 7.0, dtype=np.float32)
    write_transforms(tree, values, translation, quat)
    t64, q64 = transforms_from_values(tree, values)
    assert np.array_equal(translation[:, :m], t64.astype(np.float32))
    assert np.array_equal(quat[:, :m], q64.astype(np.float32))
    assert (translation[:, m:] == 7).all() and (quat[:, m:] == 7).all()
