"""The fitted view: the box a robot's links sweep, against yourdfpy's forward kinematics."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yourdfpy

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.robot.synth import random_urdf
from r2d2_viz.sources.base import FrameTrack
from r2d2_viz.viewer.layout.fit import AXIS_LENGTH, MANY_FRAMES, fit_view


def _box(tmp_path: Path, n_links: int, seed: int) -> tuple[Path, np.ndarray, np.ndarray]:
    urdf = tmp_path / f"r{seed}.urdf"
    urdf.write_text(random_urdf(n_links, seed=seed, joint_types=("fixed", "revolute", "prismatic"), visuals=False))
    return urdf, *_reference_box(urdf, seed)


def _reference_box(urdf: Path, seed: int) -> tuple[np.ndarray, np.ndarray]:
    model = yourdfpy.URDF.load(str(urdf), build_scene_graph=True, load_meshes=False)
    rng = np.random.default_rng(seed)
    names = model.actuated_joint_names
    configs = rng.uniform(-1, 1, (20, len(names)))
    points = []
    for cfg in configs:
        model.update_cfg(dict(zip(names, cfg, strict=True)))
        points.extend(model.get_transform(link, model.base_link)[:3, 3] for link in model.link_map)
    return np.array(points), configs


def test_the_box_is_the_links_extent_over_the_motion(tmp_path: Path) -> None:
    urdf, points, configs = _box(tmp_path, 30, seed=4)
    tree = compile_tree(load_urdf(urdf))
    names = yourdfpy.URDF.load(str(urdf), build_scene_graph=False, load_meshes=False).actuated_joint_names
    q = configs[:, [names.index(a) for a in tree.actuated]]
    fit = fit_view(tree, q)
    lo, hi = points.min(axis=0), points.max(axis=0)
    assert np.allclose(fit.center, (lo + hi) / 2, atol=1e-9)
    assert math.isclose(fit.radius, np.linalg.norm(hi - lo) / 2, rel_tol=1e-9)  # no visuals: no shape padding
    assert fit.frames == 31 and fit.show_arrows


def test_a_moving_root_moves_the_box_and_big_robots_get_smaller_axes_and_no_arrows(tmp_path: Path) -> None:
    urdf = tmp_path / "one.urdf"
    urdf.write_text(
        '<robot name="r"><link name="a"><visual><geometry><sphere radius="0.5"/></geometry></visual></link></robot>'
    )
    tree = compile_tree(load_urdf(urdf))
    # the root at (0,0,0) and at (4,0,0): box from x=0 to 4, centre x=2; radius 2 + the 0.5 m sphere
    root = FrameTrack("odom", "a", np.array([[0.0, 0, 0], [4.0, 0, 0]]), np.tile([0.0, 0, 0, 1], (2, 1)))
    fit = fit_view(tree, np.zeros((2, 0)), root=root)
    assert np.allclose(fit.center, (2, 0, 0)) and math.isclose(fit.radius, 2.5)
    assert math.isclose(fit.distance(), 1.15 * 2.5 / math.sin(math.radians(22.5)))
    chain = tmp_path / "chain.urdf"
    chain.write_text(random_urdf(MANY_FRAMES + 5, seed=1, chain=True, joint_types=("fixed",), visuals=False))
    big = fit_view(compile_tree(load_urdf(chain)), np.zeros((1, 0)))
    assert not big.show_arrows
    assert math.isclose(big.axis_length(), 0.1 * min(max(big.radius, 0.05), 20) / 2)


def test_a_scene_fit_keeps_small_groups_whole_and_trims_a_dense_groups_outliers() -> None:
    from r2d2_viz.viewer.layout.fit import fit_scene

    rng = np.random.default_rng(1)
    scan = np.column_stack([rng.uniform(0, 2, 1000), rng.uniform(0, 2, 1000), np.zeros(1000)])
    scan[0] = [500.0, 0.0, 0.0]  # one far reading: trimmed with the 2 % at either end
    marker = np.array([[-3.0, 0.0, 0.0]])  # one point: kept whole however small
    fit = fit_scene([scan, marker], robot_radius=0.1, frames=3)
    # the box is about x in [-3, 2], y in [0, 2]: centre (-0.5, 1, 0), half diagonal about sqrt(5² + 2²) / 2
    assert fit.center[0] == pytest.approx(-0.5, abs=0.1) and fit.center[1] == pytest.approx(1.0, abs=0.1)
    assert fit.radius == pytest.approx(np.hypot(5, 2) / 2 + 0.1, abs=0.1)
    assert fit.axis_length() == pytest.approx(AXIS_LENGTH * 0.1)  # TF axes follow the robot, not the scene


def test_points_beyond_float32_or_absurdly_far_are_left_out_of_a_fit_like_nan() -> None:
    # issue 29: a map lying about its size put a 6e38 m corner into the fit; the camera Rerun was given overflowed
    # float32. Such points count no more than NaN does: the fit is the one of the sane points alone.
    from r2d2_viz.viewer.layout.fit import FIT_LIMIT, fit_scene

    sane = np.array([[0.0, 0.0, 0.0], [2.0, 1.0, 0.0]])
    liars = np.array([[6e38, 6e38, 0.0], [1e300, 0.0, 0.0], [-np.inf, 0.0, 0.0], [np.nan, 0.0, 0.0]])
    with np.errstate(all="raise"):  # nothing may overflow on the way
        fit = fit_scene([sane, liars, np.array([[2 * FIT_LIMIT, 0.0, 0.0]])], robot_radius=0.1, frames=3)
    assert fit == fit_scene([sane], robot_radius=0.1, frames=3)
    assert fit.center == pytest.approx((1.0, 0.5, 0.0)) and fit.radius == pytest.approx(np.hypot(2, 1) / 2 + 0.1)
    eye = np.array(fit.center) + fit.distance()
    assert np.isfinite(eye.astype(np.float32)).all()
    only_liars = fit_scene([liars], robot_radius=0.1, frames=3)  # nothing sane: the robot's own size at the origin
    assert only_liars.center == (0.0, 0.0, 0.0) and only_liars.radius == pytest.approx(0.1)
