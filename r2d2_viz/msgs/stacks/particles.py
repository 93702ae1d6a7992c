"""nav2_msgs ParticleCloud (AMCL's particles) as nav2's RViz plugin draws it (``nav2_rviz_plugins``
``ParticleCloudDisplay``, ``FlatWeightedArrowsArray``): an arrow per particle along its pose's x, its length the
weight scaled between Min and Max Arrow Length, ``clamp(weight · (max − min) + min, min, max)`` (0.02 and 0.3 m by
default); colour (255, 25, 0), alpha 1. Shape "Arrow (Flat)" (the default): three lines a particle — the shaft to
the tip, and two head lines from the tip back to ``(0.75 L, ±0.2 L, 0)`` in the particle's frame; "Arrow (3D)":
``Arrows3D`` of the shaft plus RViz's head (``1.3043 L``), shaft radius ``0.0435 L / 2`` (of the mean ``L``: one
radius a message); "Axes": the particle's x, y, z axes, ``L`` long, red, green, blue. A message with a NaN or
an infinite value is refused whole, as the plugin refuses it.

The particles are read straight from the CDR bytes (a fixed 64-byte record each) into one numpy array.
"""

from __future__ import annotations

import struct

import numpy as np

from r2d2_viz.arrays import F64
from r2d2_viz.msgs.geometry import frame_of, one_color
from r2d2_viz.msgs.shapes import Arrows, Decoded, DecodeOptions, LineStrips, Rgba8
from r2d2_viz.msgs.typestore import MsgError

COLOR: Rgba8 = (255, 25, 0, 255)
HEAD_LENGTH = 0.3043  # RViz Arrow (3D): head length and shaft radius per unit of shaft length
SHAFT_DIAMETER = 0.0435
FLAT_HEAD = np.array([[0.75, 0.2, 0.0], [0.75, -0.2, 0.0]])  # head lines' ends per unit of length
AXIS_COLORS: tuple[Rgba8, Rgba8, Rgba8] = ((255, 0, 0, 255), (0, 255, 0, 255), (0, 0, 255, 255))
RECORD = 8  # float64 a particle: position x, y, z, orientation x, y, z, w, weight


def particles(data: bytes | memoryview) -> tuple[str, int, F64]:
    """``(frame_id, stamp_ns, (N, 8))`` of a ParticleCloud's CDR bytes: position, orientation ``xyzw``, weight."""
    if len(data) < 16 or data[0] != 0 or data[1] not in (0, 1):
        raise MsgError("not CDR")
    order = "<" if data[1] == 1 else ">"
    sec, nanosec = struct.unpack_from(order + "iI", data, 4)
    (length,) = struct.unpack_from(order + "I", data, 12)
    offset = 16 + length
    if length == 0 or offset > len(data) or data[offset - 1] != 0:
        raise MsgError("bad frame_id")
    frame = bytes(data[16 : offset - 1]).decode("utf-8", errors="replace")
    offset += -(offset - 4) % 4
    if offset + 4 > len(data):
        raise MsgError("message ends early")
    (count,) = struct.unpack_from(order + "I", data, offset)
    offset += 4
    offset += -(offset - 4) % 8 if count else 0
    if offset + 8 * RECORD * count > len(data):  # before anything of the claimed size is made
        raise MsgError(f"{count} particles in {len(data)} bytes")
    rows = np.frombuffer(data, dtype=order + "f8", count=RECORD * count, offset=offset).reshape(count, RECORD)
    return frame_of(frame), int(sec) * 1_000_000_000 + int(nanosec), rows.astype(np.float64)


def rotate(xyzw: F64, v: F64) -> F64:
    """Each vector ``v (N, 3)`` turned by its unit quaternion ``xyzw (N, 4)`` (v + 2w (q × v) + 2 q × (q × v))."""
    q, w = xyzw[:, :3], xyzw[:, 3:]
    t = 2.0 * np.cross(q, v)
    out: F64 = v + w * t + np.cross(q, t)
    return out


def decode_particle_cloud(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """Arrows of the particles, in the header frame."""
    frame, stamp, rows = particles(data)
    if not np.all(np.isfinite(rows)):
        raise MsgError("invalid floating point values (nans or infs)")
    q = rows[:, 3:7]
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    q = np.where(norm > 1e-12, q / np.where(norm > 1e-12, norm, 1.0), [0.0, 0.0, 0.0, 1.0])  # 0 reads as identity
    low, high = options.arrow_lengths
    length = np.clip(rows[:, 7] * (high - low) + low, low, high)[:, None]
    origin = rows[:, :3]
    x_axis = rotate(q, np.tile([1.0, 0.0, 0.0], (len(rows), 1)))
    color = np.array([options.display_color or COLOR], dtype=np.uint8)
    if options.particle_shape == "Axes":  # RViz's axes: x red, y green, z blue, each L long
        radius = float(np.mean(length)) * SHAFT_DIAMETER / 2 if len(rows) else 0.0
        axes = [(np.eye(3)[k], AXIS_COLORS[k]) for k in range(3)]
        return Decoded(
            frame,
            stamp,
            tuple(
                Arrows(
                    origin.astype(np.float32),
                    (rotate(q, np.tile(v, (len(rows), 1))) * length).astype(np.float32),
                    one_color(c),
                    radius,
                )
                for v, c in axes
            ),
        )
    if options.particle_shape == "Arrow (3D)":
        vectors = (x_axis * length * (1.0 + HEAD_LENGTH)).astype(np.float32)
        radius = float(np.mean(length)) * SHAFT_DIAMETER / 2 if len(rows) else 0.0
        return Decoded(frame, stamp, (Arrows(origin.astype(np.float32), vectors, color, radius),))
    tip = origin + x_axis * length
    heads = [origin + rotate(q, np.tile(end, (len(rows), 1))) * length for end in FLAT_HEAD]
    strips = np.stack([origin, tip, heads[0], tip, heads[1]], axis=1).astype(np.float32)  # shaft, then the head's V
    return Decoded(frame, stamp, (LineStrips(strips, color, 0.0),))
