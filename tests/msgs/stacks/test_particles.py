"""nav2's ParticleCloud: arrows as nav2_rviz_plugins' FlatWeightedArrowsArray draws them, from a message rosbags
wrote with the upstream .msg files (:mod:`stackbags`). The expected tips and heads are worked by hand (the first
four particles) or from the yaw angles written (the ring), not from quaternions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from stackbags import PARTICLES, T0, particle_cloud

from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.shapes import Arrows, DecodeOptions, LineStrips
from r2d2_viz.msgs.stacks.particles import decode_particle_cloud, particles
from r2d2_viz.msgs.typestore import MsgError

TYPE = "nav2_msgs/msg/ParticleCloud"

# (origin, tip, left head end, right head end) by hand: L = clamp(w · 0.28 + 0.02, 0.02, 0.3)
BY_HAND = [
    ((1, 2, 0), (1.16, 2, 0), (1.12, 2.032, 0), (1.12, 1.968, 0)),  # w 0.5: L 0.16, yaw 0
    ((0, 0, 0.5), (0, 0.3, 0.5), (-0.06, 0.225, 0.5), (0.06, 0.225, 0.5)),  # w 1: L 0.3, yaw 90°: (x, y) → (−y, x)
    ((-1, 0, 0), (-0.7, 0, 0), (-0.775, 0.06, 0), (-0.775, -0.06, 0)),  # w 2: clamped to 0.3; zero quaternion
    ((0.5, -1, 0), (0.48, -1, 0), (0.485, -1.004, 0), (0.485, -0.996, 0)),  # w −1: clamped to 0.02; yaw 180°
]


def _strips() -> np.ndarray:
    decoded = decode(TYPE, particle_cloud(T0))
    item = decoded.items[0]
    assert isinstance(item, LineStrips) and decoded.frame_id == "map" and decoded.stamp_ns == T0
    assert tuple(item.colors[0]) == (255, 25, 0, 255)  # the plugin's Color (255, 25, 0), Alpha 1
    return np.asarray(item.strips)


def test_flat_arrows_by_hand() -> None:
    strips = _strips()
    assert strips.shape == (len(PARTICLES), 5, 3)  # shaft, then the head's V: origin, tip, left, tip, right
    for k, (origin, tip, left, right) in enumerate(BY_HAND):
        np.testing.assert_allclose(strips[k], [origin, tip, left, tip, right], atol=1e-6)


def test_the_ring_from_its_yaws() -> None:
    strips = _strips()
    for k, (x, y, z, yaw, w) in enumerate(PARTICLES[4:], start=4):
        length = min(max(w * 0.28 + 0.02, 0.02), 0.3)
        c, s = math.cos(yaw), math.sin(yaw)
        np.testing.assert_allclose(strips[k, 1], [x + length * c, y + length * s, z], atol=1e-5)
        head = (0.75 * length * c - 0.2 * length * s, 0.75 * length * s + 0.2 * length * c)
        np.testing.assert_allclose(strips[k, 2, :2], [x + head[0], y + head[1]], atol=1e-5)


def test_arrow_3d_and_the_lengths() -> None:
    options = DecodeOptions(particle_shape="Arrow (3D)", arrow_lengths=(0.1, 0.5), display_color=(0, 0, 255, 128))
    item = decode_particle_cloud(particle_cloud(T0), options).items[0]
    assert isinstance(item, Arrows) and tuple(item.colors[0]) == (0, 0, 255, 128)
    # shaft L = clamp(w · 0.4 + 0.1, 0.1, 0.5) plus RViz's head 0.3043 L: w 0.5 → 0.3 · 1.3043 along +x
    np.testing.assert_allclose(item.vectors[0], [0.3 * 1.3043, 0, 0], atol=1e-6)
    np.testing.assert_allclose(item.vectors[1], [0, 0.5 * 1.3043, 0], atol=1e-6)
    np.testing.assert_allclose(item.origins[:2], [[1, 2, 0], [0, 0, 0.5]])


def test_axes() -> None:
    items = decode_particle_cloud(particle_cloud(T0), DecodeOptions(particle_shape="Axes")).items
    assert [tuple(a.colors[0]) for a in items] == [(255, 0, 0, 255), (0, 255, 0, 255), (0, 0, 255, 255)]
    assert all(isinstance(a, Arrows) for a in items)
    # particle 1: w 1 → L 0.3, yaw 90°: its x along +y, its y along −x, its z up
    np.testing.assert_allclose([a.vectors[1] for a in items], [[0, 0.3, 0], [-0.3, 0, 0], [0, 0, 0.3]], atol=1e-6)


def test_records_read_straight_from_the_bytes_match_rosbags() -> None:
    from stackbags import STORE

    frame, stamp, rows = particles(particle_cloud(T0))
    msg = STORE.deserialize_cdr(particle_cloud(T0), TYPE)
    expected = [[*(getattr(p.pose.position, a) for a in "xyz"), *(getattr(p.pose.orientation, a) for a in "xyzw"),
                 p.weight] for p in msg.particles]  # fmt: skip
    assert (frame, stamp) == ("map", T0)
    np.testing.assert_array_equal(rows, expected)


def test_nan_refused_and_truncations_fail_cleanly() -> None:
    import stackbags

    original = list(stackbags.PARTICLES)
    try:
        stackbags.PARTICLES[0] = (1.0, 2.0, 0.0, 0.0, float("nan"))
        with pytest.raises(MsgError, match="nans or infs"):
            decode(TYPE, stackbags.particle_cloud(T0))
    finally:
        stackbags.PARTICLES[:] = original
    data = particle_cloud(T0)
    for cut in (3, 10, 20, 40, len(data) - 1):
        with pytest.raises(MsgError):
            decode(TYPE, data[:cut])
    huge = bytearray(data)
    huge[4 + 8 + 4 + 4 : 4 + 8 + 4 + 4 + 4] = b"\xff\xff\xff\x7f"  # the count after "map\0": 2**31 − 1 particles
    with pytest.raises(MsgError, match="particles in"):
        decode(TYPE, bytes(huge))
