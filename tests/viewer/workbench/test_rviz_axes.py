"""RViz's Axes display (axes_display.cpp: Length 1, Radius 0.1; rviz_rendering::Axes: x red, y green, z blue)."""

from __future__ import annotations

import numpy as np

from r2d2_viz.msgs.geometry import quat_matrix
from r2d2_viz.viewer.workbench.rviz_axes import axes_drawing


def test_rvizs_defaults_three_cylinders_along_the_axes() -> None:
    drawing = axes_drawing("tool0")
    (cylinders,) = drawing.items
    assert drawing.frame_id == "tool0"
    assert cylinders.lengths.tolist() == [1.0] * 3
    np.testing.assert_allclose(cylinders.radii, [0.1] * 3)
    for q, center, axis in zip(cylinders.xyzw, cylinders.centers, np.eye(3), strict=True):
        np.testing.assert_allclose(quat_matrix(q.tolist()) @ [0.0, 0.0, 1.0], axis, atol=1e-6)
        np.testing.assert_allclose(center, axis * 0.5)
    assert cylinders.colors[:, :3].tolist() == [[255, 0, 0], [0, 255, 0], [0, 0, 255]]
