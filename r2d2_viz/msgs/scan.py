"""sensor_msgs LaserScan (vectorised over the ranges) and Range (a cone of lines)."""

from __future__ import annotations

import math

import numpy as np

from r2d2_viz.msgs.colormaps import intensity_colors
from r2d2_viz.msgs.geometry import header_of, one_color
from r2d2_viz.msgs.shapes import F32, Decoded, DecodeOptions, LineStrips, Points
from r2d2_viz.msgs.typestore import MsgError, deserialize

RANGE_COLOR = (255, 255, 255, 128)  # RViz's Range display: white, alpha 0.5
CONE_SEGMENTS = 16


def decode_laserscan(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """Points at ``angle_min + i * angle_increment``, kept as laser_geometry's ``projectLaser`` (RViz's LaserScan
    display) keeps them: ``range < range_max && range >= range_min`` (so NaN, inf and a range of exactly
    ``range_max``, a sensor's "no return", are dropped; and a non-finite point, which only ``range_min = -inf``
    could let through); coloured by ``intensities`` (RViz's rainbow over the kept points) when there is one per
    range."""
    msg = deserialize(data, "sensor_msgs/msg/LaserScan")
    frame, stamp = header_of(msg)
    ranges = np.asarray(msg.ranges, dtype=np.float32)
    intensities = np.asarray(msg.intensities, dtype=np.float32)
    if intensities.size and intensities.shape != ranges.shape:
        raise MsgError(f"{intensities.size} intensities for {ranges.size} ranges")
    with np.errstate(invalid="ignore", over="ignore"):
        angles = float(msg.angle_min) + np.arange(ranges.size, dtype=np.float64) * float(msg.angle_increment)
        keep = (ranges < msg.range_max) & (ranges >= msg.range_min) & np.isfinite(ranges) & np.isfinite(angles)
        r = ranges[keep].astype(np.float64)
        a = angles[keep]
        xyz: F32 = np.stack([r * np.cos(a), r * np.sin(a), np.zeros_like(r)], axis=1).astype(np.float32)
    by_intensity = intensities.size and options.color_transformer != "FlatColor"
    colors = intensity_colors(intensities[keep]) if by_intensity else one_color(options.flat_color)
    return Decoded(frame, stamp, (Points(xyz, colors, options.point_radius),))


def cone_strips(length: float, fov: float) -> tuple[F32, ...]:
    """A cone along +x from the origin, ``length`` long, ``fov`` wide: its base circle and four side lines."""
    if not (np.isfinite(length) and np.isfinite(fov)) or length <= 0:
        return ()
    radius = length * np.tan(min(abs(fov), np.pi * 0.999) / 2)
    t = np.linspace(0.0, 2 * np.pi, CONE_SEGMENTS + 1)
    circle = np.stack([np.full_like(t, length), radius * np.cos(t), radius * np.sin(t)], axis=1)
    sides = [np.array([[0.0, 0.0, 0.0], circle[k]]) for k in range(0, CONE_SEGMENTS, CONE_SEGMENTS // 4)]
    return tuple(s.astype(np.float32) for s in (circle, *sides))


def decode_range(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A Range as RViz draws it (RangeDisplay::processMessage): a cone along +x of angle ``field_of_view``, as
    long as ``range`` when it lies in ``[min_range, max_range]``; a fixed-distance ranger (min = max) reading -inf
    shows ``min_range``; any other reading draws nothing (an empty drawing replaces the last cone)."""
    msg = deserialize(data, "sensor_msgs/msg/Range")
    frame, stamp = header_of(msg)
    reading, low, high = float(msg.range), float(msg.min_range), float(msg.max_range)
    length = 0.0
    if low <= reading <= high:
        length = reading
    elif low == high and reading == -math.inf:
        length = low
    strips = cone_strips(length, float(msg.field_of_view)) if length > 0 else ()
    return Decoded(frame, stamp, (LineStrips(strips, one_color(RANGE_COLOR), 0.0),))
