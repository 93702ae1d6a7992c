"""vision_msgs' Detection2DArray and Detection3DArray, from messages rosbags wrote with the upstream .msg files:
corners, colours and labels by hand (the colours are vision_msgs_rviz_plugins' ``getColor``)."""

from __future__ import annotations

import math

import numpy as np
from stackbags import DETECTIONS_2D_CORNERS, T0, detections_2d, detections_3d

from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.shapes import Boxes, DecodeOptions, Outlines2D
from r2d2_viz.msgs.stacks.detections import decode_detection3d_array


def test_2d_boxes_corners_colours_labels() -> None:
    decoded = decode("vision_msgs/msg/Detection2DArray", detections_2d(T0))
    (item,) = decoded.items
    assert isinstance(item, Outlines2D) and decoded.frame_id == "cam_optical"
    np.testing.assert_allclose(item.corners, DETECTIONS_2D_CORNERS, atol=1e-5)
    assert item.labels == ("person 0.90", "")  # the best result (0.9 over car's 0.3); none: no label
    assert item.colors.tolist() == [[0, 0, 255, 255], [255, 22, 80, 255]]  # person blue; no result (255, 22, 80)


def box_corners(center: np.ndarray, half: np.ndarray, xyzw: np.ndarray) -> np.ndarray:
    """The eight corners of a box (rotation matrix of the quaternion, written out)."""
    x, y, z, w = xyzw
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    return np.asarray(center + (signs * half) @ R.T)


def test_3d_boxes_oriented_coloured_labelled() -> None:
    decoded = decode("vision_msgs/msg/Detection3DArray", detections_3d(T0))
    (item,) = decoded.items
    assert isinstance(item, Boxes) and decoded.frame_id == "map" and item.edges == 0.0
    # the car: 1 x 0.5 x 0.4 at (2, 0, 0.5), turned 90° about z: it spans 0.5 m in x and 1 m in y
    corners = box_corners(item.centers[0], item.half_sizes[0], item.xyzw[0])
    np.testing.assert_allclose(corners.min(0), [1.75, -0.5, 0.3], atol=1e-6)
    np.testing.assert_allclose(corners.max(0), [2.25, 0.5, 0.7], atol=1e-6)
    np.testing.assert_allclose(item.xyzw[0], [0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)], atol=1e-6)
    np.testing.assert_allclose(item.half_sizes[1], [0.15, 0.00005, 0.1], atol=1e-8)  # a 0 size drawn 1e-4 m
    assert item.labels == ("Car 0.75", "tree 0.50")
    assert item.colors.tolist() == [[255, 165, 0, 255], [190, 190, 190, 255]]  # "Car": car's orange; other: grey


def test_3d_only_edge_and_alpha() -> None:
    options = DecodeOptions(only_edge=True, line_width=0.08, alpha=0.5)
    (item,) = decode_detection3d_array(detections_3d(T0), options).items
    assert isinstance(item, Boxes) and item.edges == 0.08
    assert item.colors[:, 3].tolist() == [128, 128]
