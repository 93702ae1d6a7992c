"""Where decoded drawings lie in their message frame (msgs/extent), worked out by hand."""

from __future__ import annotations

import math

import numpy as np

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.extent import extent_points
from r2d2_viz.msgs.shapes import Decoded, MarkerOp, Pose

WHITE = np.array([[255, 255, 255, 255]], dtype=np.uint8)


def test_a_map_spans_its_corners_placed_by_its_origin() -> None:
    # 4 x 2 cells of 0.5 m, origin at (-1, -0.5) turned 90° about z: corner (2, 0) goes to (-1, 1.5)
    grid = shapes.GridMap(
        np.zeros((2, 4, 4), np.uint8),
        0.5,
        Pose((-1.0, -0.5, 0.0), (0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4))),
    )
    got = extent_points(Decoded("map", 0, (grid,)))
    np.testing.assert_allclose(got, [[-1, -0.5, 0], [-1, 1.5, 0], [-2, 1.5, 0], [-2, -0.5, 0]], atol=1e-12)


def test_points_markers_and_non_finite_values() -> None:
    points = shapes.Points(np.array([[1, 2, 3], [np.nan, 0, 0]], np.float32), WHITE, 0.01, Pose((1.0, 0.0, 0.0)))
    assert extent_points(Decoded("laser", 0, (points,))).tolist() == [[2, 2, 3]]  # NaN left out; shifted by 1 m
    cube = shapes.Boxes(
        np.array([[0, 0, 1]], np.float32), np.ones((1, 3), np.float32), np.array([[0, 0, 0, 1]], np.float32), WHITE
    )
    ops = [MarkerOp("add", "a", 1, Decoded("odom", 0, (cube,))), MarkerOp("delete", "a", 2)]
    assert extent_points(ops).tolist() == [[0, 0, 1]]
    image = shapes.CompressedImage(b"", "image/jpeg")
    assert extent_points(Decoded("camera", 0, (image,))).shape == (0, 3)  # no place in 3D


def test_maps_can_be_left_out() -> None:
    grid = shapes.GridMap(np.zeros((2, 2, 4), np.uint8), 1.0)
    assert extent_points(Decoded("map", 0, (grid,)), maps=False).shape == (0, 3)
    assert extent_points(Decoded("map", 0, (grid,))).shape == (4, 3)
