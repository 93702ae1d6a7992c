"""Quaternion maths against SciPy's Rotation (xyzw, like ours), including rotations near 180°."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from r2d2_viz.kinematics.transforms import matrix_to_quat, quat_from_axis_angle, quat_multiply, quat_to_matrix


def _same_rotation(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.allclose(np.abs(np.sum(a * b, axis=-1)), 1.0, atol=1e-12))  # q and −q are one rotation


def test_against_scipy() -> None:
    rng = np.random.default_rng(3)
    a, b = Rotation.random(500, random_state=4), Rotation.random(500, random_state=5)
    qa, qb = a.as_quat(), b.as_quat()  # xyzw
    assert np.allclose(quat_to_matrix(qa), a.as_matrix(), atol=1e-12)
    assert _same_rotation(quat_multiply(qa, qb), (a * b).as_quat())
    assert _same_rotation(matrix_to_quat(a.as_matrix()), qa)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    angles = rng.uniform(-7, 7, 100)
    assert _same_rotation(quat_from_axis_angle(axis, angles), Rotation.from_rotvec(angles[:, None] * axis).as_quat())


def test_matrix_to_quat_near_half_turns_and_w_is_not_negative() -> None:
    near = Rotation.from_rotvec(np.array([[np.pi - 1e-9, 0, 0], [0, np.pi, 0], [0, 0, -np.pi + 1e-7], [1e-12, 0, 0]]))
    q = matrix_to_quat(near.as_matrix())
    assert _same_rotation(q, near.as_quat()) and np.all(q[:, 3] >= 0)


def test_a_zero_quaternion_gives_nan_silently() -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = quat_to_matrix(np.array([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 2.0]]))
    assert np.isnan(out[0]).all()
    assert np.array_equal(out[1], np.eye(3))
