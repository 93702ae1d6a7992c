"""The optimised hot paths against their literal forms (issue #4: same values, only faster)."""

from __future__ import annotations

import numpy as np
from reference import state_publisher_bounces

from r2d2_viz.kinematics.transforms import quat_multiply
from r2d2_viz.kinematics.tree import compile_tree, joint_transforms, moving_values
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.robot.synth import random_urdf
from r2d2_viz.sources.motion import (
    HEIGHT_LOWER,
    HEIGHT_START,
    HEIGHT_STEP,
    HEIGHT_UPPER,
    TILT_LOWER,
    TILT_START,
    TILT_STEP,
    TILT_UPPER,
    bounce_cycle,
)

DAY_SAMPLES = 24 * 3600 * 30


def _at(cycle: tuple[np.ndarray, int], frame: np.ndarray) -> np.ndarray:
    values, loop = cycle
    return values[np.where(frame < len(values), frame, loop + (frame - loop) % (len(values) - loop))]


def test_bounce_cycle_is_the_literal_loop_bit_for_bit_over_a_day() -> None:
    tilts, heights = (np.array(v) for v in state_publisher_bounces(DAY_SAMPLES))
    frame = np.arange(DAY_SAMPLES)
    tilt = _at(bounce_cycle(TILT_START, TILT_STEP, TILT_LOWER, TILT_UPPER), frame)
    height = _at(bounce_cycle(HEIGHT_START, HEIGHT_STEP, HEIGHT_LOWER, HEIGHT_UPPER), frame)
    assert tilt.tobytes() == tilts.tobytes()
    assert height.tobytes() == heights.tobytes()


def test_joint_transforms_equal_composing_quaternions_per_frame(tmp_path) -> None:
    for seed, chain in ((1, False), (2, True), (3, False)):
        urdf = tmp_path / f"r{seed}.urdf"
        urdf.write_text(random_urdf(40, seed=seed, chain=chain))
        tree = compile_tree(load_urdf(urdf))
        q = np.random.default_rng(seed).uniform(-4, 4, (257, len(tree.actuated)))
        translation, quat = joint_transforms(tree, q)
        # the literal form: origin ⊗ rot(axis, angle); t = t_origin + R_origin · (axis · d)
        values = moving_values(tree, q)
        revolute = tree.moving_kind == 0
        half = np.where(revolute, values, 0.0)[..., None] / 2
        q_motion = np.concatenate([np.sin(half) * tree.moving_axis, np.cos(half)], axis=-1)
        expected_q = quat_multiply(tree.moving_origin_q, q_motion)
        shift = np.where(revolute, 0.0, values)[..., None] * tree.moving_axis
        expected_t = tree.moving_origin_t + np.einsum("mij,tmj->tmi", tree.moving_origin_R, shift)
        assert translation.shape == expected_t.shape and quat.shape == expected_q.shape
        assert np.allclose(translation, expected_t, rtol=0, atol=1e-12)
        assert np.allclose(quat, expected_q, rtol=0, atol=1e-12)
