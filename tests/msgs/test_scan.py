"""LaserScan and Range decoding against hand-computed geometry and RViz's intensity colouring."""

from __future__ import annotations

import math

import numpy as np
import pytest
from msgs_build import T, cdr, header, rviz_intensity

from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.scan import decode_laserscan, decode_range
from r2d2_viz.msgs.shapes import DecodeOptions, LineStrips, Points
from r2d2_viz.msgs.typestore import MsgError

OPTIONS = DecodeOptions()


def scan(ranges: list[float], intensities: list[float] | None = None, frame: str = "/base_laser") -> bytes:
    msg = T("sensor_msgs/msg/LaserScan")(
        header=header(frame, 7, 500_000_000),
        angle_min=-math.pi / 2,
        angle_max=math.pi / 2,
        angle_increment=math.pi / 2,
        time_increment=0.0,
        scan_time=0.1,
        range_min=0.5,
        range_max=10.0,
        ranges=np.array(ranges, dtype=np.float32),
        intensities=np.array(intensities or [], dtype=np.float32),
    )
    return cdr(msg)


def test_points_at_their_angles_with_nan_inf_and_out_of_range_dropped() -> None:
    # beams at -90°, 0°, +90°, 180°, 270°, …: 1 m, NaN, 2 m, 0.2 m (< range_min), inf, 11 m (> range_max), 10 m
    # (= range_max: no return, dropped), 9.5 m, 0.5 m (= range_min: kept)
    decoded = decode_laserscan(scan([1.0, math.nan, 2.0, 0.2, math.inf, 11.0, 10.0, 9.5, 0.5]), OPTIONS)
    assert decoded.frame_id == "base_laser"  # leading '/' dropped, as tf2 does
    assert decoded.stamp_ns == 7_500_000_000
    (points,) = decoded.items
    assert isinstance(points, Points)
    # by hand: beam 0 at -90° → (0, -1); beam 2 at +90° → (0, 2); beam 7 at -90° + 7·90° = 540° ≡ 180° → (-9.5, 0);
    # beam 8 at 630° ≡ 270° → (0, -0.5)
    expected = [[0, -1, 0], [0, 2, 0], [-9.5, 0, 0], [0, -0.5, 0]]
    np.testing.assert_allclose(points.positions, expected, atol=1e-5)  # float32 angles
    assert points.colors.tolist() == [[255, 255, 255, 255]]  # no intensities: one flat colour


def _laser_geometry_kept(ranges: list[float], range_min: float, range_max: float) -> list[int]:
    """laser_geometry's keep-test, transcribed (ros-perception/laser_geometry, ROS 2 branch):
    src/laser_geometry.cpp, ``LaserProjection::projectLaser_``::

        if (range_cutoff < 0) { range_cutoff = scan_in.range_max; }
        ...
        const float range = scan_in.ranges[i];
        if (range < range_cutoff && range >= scan_in.range_min) {

    and src/laser_geometry/laser_geometry.py, ``__projectLaser``: ``if ri < range_cutoff and ri >= scan_in.range_min``
    (``range_cutoff`` -1, RViz's LaserScan display's call, becomes ``range_max``). The ranges and limits are floats."""
    f = np.float32
    return [i for i, r in enumerate(ranges) if f(r) < f(range_max) and f(r) >= f(range_min)]


def test_the_rays_kept_are_laser_geometrys() -> None:
    ranges = [0.4999, 0.5, 0.5001, 5.0, 9.9999, 10.0, 10.0001, math.inf, -math.inf, math.nan, 0.0, -1.0]
    expected = _laser_geometry_kept(ranges, 0.5, 10.0)
    assert expected == [1, 2, 3, 4]  # by hand: range_min itself in, range_max itself out
    (points,) = decode_laserscan(scan(ranges), OPTIONS).items
    assert isinstance(points, Points)
    beams = -math.pi / 2 + np.array(expected) * math.pi / 2  # each kept beam's angle and range, back from its point
    r = np.float32(ranges)[expected]
    np.testing.assert_allclose(points.positions[:, :2], np.stack([r * np.cos(beams), r * np.sin(beams)], 1), atol=1e-5)


def test_intensities_colour_the_kept_points_with_rvizs_rainbow() -> None:
    decoded = decode_laserscan(scan([1.0, math.nan, 2.0, 3.0], [10.0, 999.0, 20.0, 40.0]), OPTIONS)
    (points,) = decoded.items
    assert isinstance(points, Points)
    # the NaN beam is dropped before the bounds are computed (RViz projects the scan first): bounds 10..40
    expected = rviz_intensity([10.0, 20.0, 40.0])
    assert [tuple(c[:3]) for c in points.colors.tolist()] == expected
    assert expected[0] == (255, 0, 0) and expected[-1] == (255, 0, 255)  # min red, max magenta
    assert points.colors[:, 3].tolist() == [255, 255, 255]


def test_all_invalid_is_empty_and_mismatched_intensities_refused() -> None:
    (points,) = decode_laserscan(scan([math.nan, math.inf]), OPTIONS).items
    assert isinstance(points, Points) and points.positions.shape == (0, 3)
    with pytest.raises(MsgError, match="intensities"):
        decode_laserscan(scan([1.0, 2.0], [1.0]), OPTIONS)


@pytest.mark.parametrize("cut", [0, 3, 10, 40])
def test_truncated_bytes_raise_value_error(cut: int) -> None:
    data = scan([1.0, 2.0, 3.0])
    with pytest.raises(ValueError):
        decode("sensor_msgs/msg/LaserScan", data[:cut])


def test_huge_claimed_array_does_not_allocate() -> None:
    data = bytearray(scan([1.0]))
    # the ranges length field sits right before the last 4+4+4 bytes (1 float range, empty intensities length)
    data[-12:-8] = (0x7FFFFFFF).to_bytes(4, "little")
    with pytest.raises(ValueError):
        decode("sensor_msgs/msg/LaserScan", bytes(data))


def test_range_is_a_cone_along_x() -> None:
    msg = T("sensor_msgs/msg/Range")(
        header=header("sonar"),
        radiation_type=0,
        field_of_view=math.pi / 2,
        min_range=0.1,
        max_range=4.0,
        range=2.0,
    )
    (strips,) = decode_range(cdr(msg), OPTIONS).items
    assert isinstance(strips, LineStrips)
    circle, *sides = strips.strips
    # fov 90°: the base circle at x = 2 has radius 2·tan(45°) = 2
    np.testing.assert_allclose(circle[:, 0], 2.0)
    np.testing.assert_allclose(np.hypot(circle[:, 1], circle[:, 2]), 2.0, rtol=1e-6)
    assert len(sides) == 4 and all(np.allclose(s[0], 0.0) for s in sides)


@pytest.mark.parametrize(
    ("reading", "low", "high", "length"),
    [
        (5.0, 0.1, 4.0, 0.0),  # beyond max_range: RViz draws nothing (RangeDisplay::processMessage)
        (0.05, 0.1, 4.0, 0.0),  # below min_range: nothing
        (float("nan"), 0.1, 4.0, 0.0),
        (-math.inf, 0.3, 0.3, 0.3),  # a fixed-distance ranger (min = max) reading -inf: min_range
        (math.inf, 0.3, 0.3, 0.0),
        (4.0, 0.1, 4.0, 4.0),  # the bounds themselves are in range
    ],
)
def test_range_readings_outside_their_limits_as_rviz_shows_them(
    reading: float, low: float, high: float, length: float
) -> None:
    msg = T("sensor_msgs/msg/Range")(
        header=header("sonar"), radiation_type=0, field_of_view=0.2, min_range=low, max_range=high, range=reading
    )
    (strips,) = decode_range(cdr(msg), OPTIONS).items
    assert isinstance(strips, LineStrips)
    if length == 0.0:
        assert strips.strips == ()
    else:
        assert max(float(s[:, 0].max()) for s in strips.strips) == pytest.approx(length)
