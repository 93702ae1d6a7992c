"""AccelStamped as RViz 2's AccelStamped display: the Twist display's two arrows (linear, angular), x 1."""

from __future__ import annotations

import numpy as np
import pytest
from msgs_build import T, cdr, header, vec

from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.shapes import Arrows
from r2d2_viz.msgs.typestore import MsgError


def _accel(linear: tuple[float, float, float], angular: tuple[float, float, float]) -> bytes:
    accel = T("geometry_msgs/msg/Accel")(linear=vec(*linear), angular=vec(*angular))
    return cdr(T("geometry_msgs/msg/AccelStamped")(header=header("imu", 3, 4), accel=accel))


def test_linear_then_angular_arrow_in_the_header_frame() -> None:
    decoded = decode("geometry_msgs/msg/AccelStamped", _accel((0.5, 0.0, -9.8), (0.0, 0.1, 0.0)))
    assert decoded.frame_id == "imu" and decoded.stamp_ns == 3_000_000_004
    linear, angular = decoded.items
    assert isinstance(linear, Arrows) and isinstance(angular, Arrows)
    np.testing.assert_allclose(linear.vectors, [[0.5, 0.0, -9.8]], rtol=1e-6)
    np.testing.assert_allclose(angular.vectors, [[0.0, 0.1, 0.0]], rtol=1e-6)
    assert linear.colors.tolist() == [[204, 51, 51, 255]] and angular.colors.tolist() == [[204, 204, 51, 255]]


def test_a_non_finite_vector_or_a_cut_message_is_refused() -> None:
    with pytest.raises(MsgError):
        decode("geometry_msgs/msg/AccelStamped", _accel((float("nan"), 0.0, 0.0), (0.0, 0.0, 0.0)))
    with pytest.raises(MsgError):
        decode("geometry_msgs/msg/AccelStamped", _accel((1.0, 0.0, 0.0), (0.0, 0.0, 0.0))[:20])
