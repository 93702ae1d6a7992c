"""The display-data classes: frozen, identity pose by default, RViz's display defaults in DecodeOptions."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from r2d2_viz.msgs.shapes import IDENTITY, Decoded, DecodeOptions, MarkerOp, Points, Pose


def test_frozen_with_identity_pose() -> None:
    points = Points(np.zeros((1, 3), np.float32), np.zeros((1, 4), np.uint8), 0.1)
    assert points.T_frame_item == IDENTITY == Pose((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))  # xyzw
    with pytest.raises(dataclasses.FrozenInstanceError):
        points.radius = 1.0  # type: ignore[misc]
    assert Decoded("map", 0).items == ()
    assert MarkerOp("delete", "ns", 1).decoded is None


def test_options_defaults() -> None:
    options = DecodeOptions()
    # RViz: Map display colour scheme 'map', point Size 0.01 m (a diameter), covariance scale 1 (1 sigma)
    assert (options.map_scheme, options.point_radius, options.covariance_scale) == ("map", 0.005, 1.0)
