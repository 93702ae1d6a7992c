"""Frames, quaternions (xyzw) and colours."""

from __future__ import annotations

import math

import numpy as np
import pytest
from msgs_build import color, quat, vec

from r2d2_viz.msgs.geometry import frame_of, matrix_quat, quat_matrix, rgba8, xyz, xyzw
from r2d2_viz.msgs.typestore import MsgError


def test_frame_ids_as_tf2_keys_them() -> None:
    assert [frame_of(f) for f in ["/map", "map", "", "//x", "a/b"]] == ["map", "map", "", "/x", "a/b"]


def test_quaternions() -> None:
    assert xyzw(quat(0, 0, 0, 0)) == (0.0, 0.0, 0.0, 1.0)  # RViz draws an all-zero quaternion as identity
    assert xyzw(quat(0, 0, 0, 2)) == (0.0, 0.0, 0.0, 1.0)  # normalised
    with pytest.raises(MsgError):
        xyzw(quat(math.nan, 0, 0, 1))
    # 90° about z maps x to y (by hand)
    q = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))
    np.testing.assert_allclose(quat_matrix(q) @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    rng = np.random.default_rng(1)
    for _ in range(20):
        v = rng.normal(size=4)
        v /= np.linalg.norm(v)
        back = np.array(matrix_quat(quat_matrix(tuple(v))))
        assert np.allclose(back, v) or np.allclose(back, -v)


def test_colours() -> None:
    assert rgba8(color(1.0, 0.5, 0.0, 2.0)) == (255, 128, 0, 255)  # clipped to [0, 1]
    assert rgba8(color(math.nan, 0.2, 0.0, 1.0)) == (0, 51, 0, 255)


def test_vectors_the_viewer_cannot_hold_are_refused() -> None:
    """3.4028235e38 is float32's largest finite value (IEEE 754 binary32: (2 − 2⁻²³) · 2¹²⁷)."""
    assert xyz(vec(3.4e38, -3.4e38, 0)) == (3.4e38, -3.4e38, 0.0)
    for lie in (1e300, -1e39, math.inf, math.nan):
        with pytest.raises(MsgError, match="non-finite vector"):
            xyz(vec(0, lie, 0))
