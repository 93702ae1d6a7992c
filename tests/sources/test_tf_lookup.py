"""tf2's lookup over recorded transforms (sources/tf_lookup), against poses composed by hand."""

from __future__ import annotations

import math

import numpy as np

from r2d2_viz.sources.base import TfRecords
from r2d2_viz.sources.tf_lookup import frame_pose, frame_positions

S = 1_000_000_000
Z90 = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))  # 90° about z, xyzw


def _records() -> list[TfRecords]:
    # odom → base_link moving: x = 1 m at t = 1 s, 2 m at t = 2 s, turned 90° at t = 2 s;
    # base_link → laser static: 0.5 m ahead; lost → nowhere: a frame the tree does not join to odom
    moving = TfRecords(
        np.array([1 * S, 2 * S]),
        ("odom", "odom"),
        ("base_link", "base_link"),
        np.array([[1.0, 0, 0], [2.0, 0, 0]]),
        np.array([[0, 0, 0, 1.0], Z90]),
    )
    static = TfRecords(
        np.array([0, 0]),
        ("base_link", "nowhere"),
        ("laser", "lost"),
        np.array([[0.5, 0, 0], [0, 0, 0]]),
        np.array([[0, 0, 0, 1.0], [0, 0, 0, 1.0]]),
        static=True,
    )
    return [moving, static]


def test_latest_value_at_each_time_composed_up_the_chain() -> None:
    times = np.array([S, S + S // 2, 2 * S, 3 * S])
    got = frame_positions(_records(), "odom", ["laser", "base_link", "lost"], times)
    assert set(got) == {"laser", "base_link"}  # 'lost' hangs under 'nowhere', not under odom
    # laser = base + R_base · (0.5, 0, 0): unturned until 2 s, then turned 90° (its 0.5 m points along +y)
    np.testing.assert_allclose(got["laser"], [[1.5, 0, 0], [1.5, 0, 0], [2, 0.5, 0], [2, 0.5, 0]], atol=1e-12)
    np.testing.assert_allclose(got["base_link"][:, 0], [1, 1, 2, 2])
    translation, quat = frame_pose(_records(), "odom", "laser", np.array([2 * S]))  # type: ignore[misc]
    np.testing.assert_allclose(translation[0], [2, 0.5, 0], atol=1e-12)
    np.testing.assert_allclose(quat[0], Z90, atol=1e-12)


def test_a_cycle_in_hostile_data_is_no_pose() -> None:
    loop = TfRecords(np.array([0, 0]), ("a", "b"), ("b", "a"), np.zeros((2, 3)), np.tile([0, 0, 0, 1.0], (2, 1)))
    assert frame_pose([loop], "odom", "a", np.array([0])) is None


def test_a_lookup_built_once_answers_as_frame_pose() -> None:
    from r2d2_viz.sources.base import TfRecords
    from r2d2_viz.sources.tf_lookup import TfLookup, frame_pose

    records = [
        TfRecords(
            np.array([0, 10], dtype=np.int64),
            ("odom", "odom"),
            ("base", "base"),
            np.array([[1.0, 0, 0], [2.0, 0, 0]]),
            np.array([[0, 0, 0, 1.0], [0, 0, 0, 1.0]]),
        )
    ]
    times = np.array([0, 5, 10, 20], dtype=np.int64)
    got, want = TfLookup(records).pose("odom", "base", times), frame_pose(records, "odom", "base", times)
    assert got is not None and want is not None
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[0][:, 0], [1, 1, 2, 2])  # the latest at or before each time, by hand
    assert TfLookup(records).pose("odom", "nowhere", times) is None
