"""Depth → points as RViz's DepthCloud (rviz_common/src/rviz_common/depth_cloud_mld.cpp, MultiLayerDepth): the
projection from P with binning and ROI, 16UC1 in mm (0: none), 32FC1 in m (any finite value, 0 included); the
values below by hand."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from r2d2_viz.msgs.rviz2.depth_cloud import depth_points, projection_of
from r2d2_viz.msgs.shapes import Image
from r2d2_viz.msgs.typestore import MsgError


def _info(p: list[float], binning: int = 0, roi: tuple[int, int] = (0, 0)) -> SimpleNamespace:
    return SimpleNamespace(
        p=p, binning_x=binning, binning_y=binning, roi=SimpleNamespace(x_offset=roi[0], y_offset=roi[1])
    )


P = [4.0, 0.0, 2.0, 0.0, 0.0, 8.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]


def test_float_depth_keeps_zero_and_drops_nan() -> None:
    depth = Image(np.array([[0.0, np.nan, 2.0]], dtype=np.float32), "L", "32FC1")
    points = depth_points(depth, projection_of(_info(P)))
    # (u - cx) d / fx, (v - cy) d / fy, d with cx 2, cy 1, fx 4, fy 8: u = 0 at 0 m, u = 2 at 2 m (row 0)
    np.testing.assert_allclose(points.positions, [[0.0, 0.0, 0.0], [0.0, -0.25, 2.0]])
    assert points.colors.tolist() == [[255, 255, 255, 255]]  # no colour image: white


def test_binning_and_roi_move_the_principal_point() -> None:
    projection = projection_of(_info(P, binning=2, roi=(2, 1)))
    # fx = 4 / 2, cx = (2 - 2) / 2, fy = 8 / 2, cy = (1 - 1) / 2
    assert (projection.fx, projection.cx, projection.fy, projection.cy) == (2.0, 0.0, 4.0, 0.0)
    depth = Image(np.array([[1000, 0]], dtype=np.uint16), "L", "16UC1")
    np.testing.assert_allclose(depth_points(depth, projection).positions, [[0.0, 0.0, 1.0]])


def test_a_bgr_image_of_the_same_size_colours_the_points_another_size_does_not() -> None:
    depth = Image(np.array([[1000, 2000]], dtype=np.uint16), "L", "16UC1")
    bgr = Image(np.array([[[1, 2, 3], [4, 5, 6]]], dtype=np.uint8), "BGR", "bgr8")
    points = depth_points(depth, projection_of(_info(P)), bgr)
    assert points.colors.tolist() == [[3, 2, 1, 255], [6, 5, 4, 255]]
    wrong = Image(np.zeros((2, 2, 3), dtype=np.uint8), "RGB", "rgb8")
    assert depth_points(depth, projection_of(_info(P)), wrong).colors.tolist() == [[255, 255, 255, 255]]


def test_what_is_refused() -> None:
    with pytest.raises(MsgError, match="projection"):
        projection_of(_info([0.0] * 12))
    with pytest.raises(MsgError, match="16UC1 or 32FC1"):
        depth_points(Image(np.zeros((2, 2, 3), np.uint8), "RGB", "rgb8"), projection_of(_info(P)))
