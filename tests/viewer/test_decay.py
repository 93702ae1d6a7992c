"""Decayed displays' drawings put into the fixed frame at their stamp (RViz keeps each cloud where it was
received). Expected coordinates worked out by hand from the transforms written here."""

from __future__ import annotations

import numpy as np

from r2d2_viz.msgs.shapes import IDENTITY, Arrows, Boxes, Decoded, Points, Pose
from r2d2_viz.sources.base import TfRecords
from r2d2_viz.viewer.decay import FixedFramePlacer

S = 1_000_000_000
YAW_90 = (0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5))  # xyzw: +90 degrees about z


def _tf() -> list[TfRecords]:
    """odom → base_link: at x = 1 from t = 0, at x = 3 from t = 2 s, turned +90° about z; base_link → laser
    (static): 0.5 m ahead."""
    moving = TfRecords(
        np.array([0, 2 * S], dtype=np.int64),
        ("odom", "odom"),
        ("base_link", "base_link"),
        np.array([[1.0, 0, 0], [3.0, 0, 0]]),
        np.array([YAW_90, YAW_90]),
    )
    static = TfRecords(
        np.zeros(1, np.int64), ("base_link",), ("laser",), np.array([[0.5, 0, 0]]), np.array([[0, 0, 0, 1.0]]), True
    )
    return [static, moving]


def _points(frame: str, stamp: int, positions, pose: Pose = IDENTITY) -> Decoded:
    cloud = Points(np.array(positions, dtype=np.float32), np.zeros((0, 4), np.uint8), 0.01, pose)
    return Decoded(frame, stamp, (cloud,))


def test_points_go_into_the_fixed_frame_where_their_frame_was_at_their_stamp() -> None:
    placer = FixedFramePlacer(_tf(), "odom")
    # laser at t = 1 s: base_link at (1, 0) turned 90°, laser 0.5 m ahead of it → (1, 0.5); its +x is odom's +y
    placed = placer.place(_points("laser", 1 * S, [[1, 0, 0], [0, 1, 0]]), 1 * S)
    assert placed.frame_id == "odom"
    np.testing.assert_allclose(placed.items[0].positions, [[1, 1.5, 0], [0, 0.5, 0]], atol=1e-6)
    # at t = 2.5 s base_link is at (3, 0): the same scan lands 2 m further along x
    later = placer.place(_points("laser", 0, [[1, 0, 0]]), 2_500_000_000)  # no stamp: the receive time
    np.testing.assert_allclose(later.items[0].positions, [[3, 1.5, 0]], atol=1e-6)
    # an item pose inside the frame is applied first: (1, 0, 0) shifted by (0, 0, 2) in the laser frame
    shifted = placer.place(_points("laser", S, [[1, 0, 0]], Pose((0.0, 0.0, 2.0))), S)
    np.testing.assert_allclose(shifted.items[0].positions, [[1, 1.5, 2]], atol=1e-6)


def test_arrows_turn_with_their_frame() -> None:
    arrows = Arrows(np.zeros((1, 3), np.float32), np.array([[1, 0, 0]], np.float32), np.zeros((0, 4), np.uint8), 0.1)
    placed = FixedFramePlacer(_tf(), "odom").place(Decoded("base_link", S, (arrows,)), S)
    np.testing.assert_allclose(placed.items[0].origins, [[1, 0, 0]], atol=1e-6)
    np.testing.assert_allclose(placed.items[0].vectors, [[0, 1, 0]], atol=1e-6)  # base_link's +x is odom's +y


def test_what_cannot_be_placed_stays_in_its_own_frame() -> None:
    placer = FixedFramePlacer(_tf(), "odom")
    unknown = _points("camera", S, [[1, 0, 0]])  # no transform reaches it
    assert placer.place(unknown, S) is unknown
    box = Boxes(
        np.zeros((1, 3), np.float32),
        np.ones((1, 3), np.float32),
        np.array([[0, 0, 0, 1.0]]),
        np.zeros((0, 4), np.uint8),
    )
    solid = Decoded("laser", S, (box,))  # solids keep their frame (their pose is an item pose)
    assert placer.place(solid, S) is solid
