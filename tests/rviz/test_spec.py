"""What an RViz config says, as data, and RViz's camera maths (r2d2_viz.rviz.spec); values worked out by hand."""

from __future__ import annotations

import math

import pytest

from r2d2_viz.rviz.config import parse_rviz
from r2d2_viz.rviz.spec import orbit_eye, orbit_view, short_class


def test_orbit_eye_by_hand() -> None:
    # yaw 90°, pitch 0, distance 2 from (1, 0, 0): the eye stands at (1, 2, 0)
    assert orbit_eye((1.0, 0.0, 0.0), 2.0, math.pi / 2, 0.0) == pytest.approx((1.0, 2.0, 0.0))
    # pitch 90°: straight above the focal point
    assert orbit_eye((0.0, 0.0, 1.0), 3.0, 0.3, math.pi / 2) == pytest.approx((0.0, 0.0, 4.0))


def test_orbit_view_lift_moves_eye_and_target_along_the_cameras_up() -> None:
    # yaw 0, pitch 0, distance 10: the camera looks along -X, its up is +Z; a 0.2 lift raises both by 2 m
    eye, target, up = orbit_view((0.0, 0.0, 0.0), 10.0, 0.0, 0.0, lift=0.2)
    assert eye == pytest.approx((10.0, 0.0, 2.0))
    assert target == pytest.approx((0.0, 0.0, 2.0))
    assert up == (0.0, 0.0, 1.0)
    # Invert Z Axis: yaw and pitch negated, up is -Z
    eye, _, up = orbit_view((0.0, 0.0, 0.0), 1.0, math.pi / 2, 0.5, invert_z=True)
    assert eye == pytest.approx((0.0, -math.cos(0.5), -math.sin(0.5)))
    assert up == (0.0, 0.0, -1.0)


def test_short_class() -> None:
    assert short_class("rviz_default_plugins/Grid") == "Grid"
    assert short_class("rviz/Grid") == "Grid"
    assert short_class(None) == ""


def test_missing_fixed_frame_uses_rvizs_words() -> None:
    from r2d2_viz.rviz.spec import missing_fixed_frame_warning

    spec = parse_rviz("Visualization Manager:\n  Global Options:\n    Fixed Frame: map\n", source="m.rviz")
    assert missing_fixed_frame_warning(spec, iter(["odom", "base_link"])) == (
        "m.rviz: Fixed Frame [map] does not exist; the view opens on it all the same"
    )
    assert missing_fixed_frame_warning(spec, ["map"]) is None
