"""The source seam: joint state carried forward like robot_state_publisher, arrays as a source, the TF root."""

from __future__ import annotations

import numpy as np
import pytest

from r2d2_viz.sources.base import (
    ArraySource,
    FrameTrack,
    JointState,
    SampleChunk,
    TfRecords,
    last_per_time,
    tf_root,
)


def _loop_reference(joints, chunks):
    """robot_state_publisher's rule written as a plain loop: a joint keeps its last value (0 before any)."""
    last = dict.fromkeys(joints, 0.0)
    rows = []
    for names, positions in chunks:
        for row in positions:
            for name, value in zip(names, row, strict=True):
                if not np.isnan(value):
                    last[name] = float(value)
            rows.append([last[j] for j in joints])
    return np.array(rows)


def test_missing_values_keep_the_last_one_across_chunks() -> None:
    joints = ("a", "b", "c", "d")
    rng = np.random.default_rng(7)
    chunks = []
    for _ in range(6):
        names = tuple(rng.permutation(joints)[: rng.integers(1, 5)])  # any subset, any order
        positions = rng.normal(size=(int(rng.integers(1, 40)), len(names)))
        positions[rng.random(positions.shape) < 0.4] = np.nan  # and samples that leave joints out
        chunks.append((names, positions))
    state = JointState(joints)
    got = np.vstack(
        [
            state.update(SampleChunk(np.arange(len(p), dtype=np.int64) + 100 * k, n, p))
            for k, (n, p) in enumerate(chunks)
        ]
    )
    assert np.array_equal(got, _loop_reference(joints, chunks))


def test_an_unknown_joint_is_named_with_the_valid_ones() -> None:
    with pytest.raises(KeyError, match="no actuated joint 'z'; actuated joints are a, b"):
        JointState(("a", "b")).columns(["z"])


def test_array_source_hands_out_bounded_chunks_of_the_same_samples() -> None:
    n = 25
    times = np.arange(n, dtype=np.int64) * 10
    positions = np.arange(n * 2, dtype=np.float64).reshape(n, 2)
    track = FrameTrack("odom", "base", np.zeros((n, 3)) + np.arange(n)[:, None], np.tile([0.0, 0, 0, 1], (n, 1)))
    source = ArraySource(times, ["x", "y"], positions, tracks=[track])
    chunks = list(source.chunks(10))
    assert [len(c) for c in chunks] == [10, 10, 5] and source.frames == (("odom", "base"),)
    assert np.array_equal(np.concatenate([c.times_ns for c in chunks]), times)
    assert np.array_equal(np.vstack([c.positions for c in chunks]), positions)
    assert np.array_equal(np.vstack([c.frames[0].translation for c in chunks]), track.translation)
    with pytest.raises(ValueError, match="25 times need positions of shape"):
        ArraySource(times, ["x"], positions)


def test_the_tf_root_is_the_frame_with_no_parent_and_most_below() -> None:
    def records(edges):
        n = len(edges)
        return TfRecords(
            np.zeros(n, dtype=np.int64),
            tuple(p for p, _ in edges),
            tuple(c for _, c in edges),
            np.zeros((n, 3)),
            np.tile([0.0, 0, 0, 1], (n, 1)),
        )

    assert tf_root([records([("map", "odom"), ("odom", "base_link")]), records([("base_link", "laser")])]) == "map"
    assert tf_root([records([("world", "a"), ("map", "odom"), ("odom", "base")])]) == "map"  # two trees: the bigger
    assert tf_root([]) is None


def test_tf_records_rows_keeps_the_rows_asked_for() -> None:
    import numpy as np

    from r2d2_viz.sources.base import TfRecords

    r = TfRecords(np.array([1, 2, 3]), ("a", "b", "c"), ("x", "y", "z"), np.eye(3), np.tile([0, 0, 0, 1.0], (3, 1)))
    kept = r.rows(np.array([0, 2]))
    assert kept.times_ns.tolist() == [1, 3] and kept.parents == ("a", "c") and kept.children == ("x", "z")
    assert kept.translation.tolist() == [[1, 0, 0], [0, 0, 1]] and not kept.static


def test_samples_sharing_a_time_become_the_last_with_what_it_leaves_out_from_before() -> None:
    """By hand: at t=2 three samples (a and b; b only; a only) leave a from the third, b from the second."""
    nan = np.nan
    times = np.array([1, 2, 2, 2, 3, 3], dtype=np.int64)
    positions = np.array([[0.0, 0.0], [1.0, 1.0], [nan, 2.0], [3.0, nan], [nan, nan], [nan, 5.0]])
    track = FrameTrack("odom", "base", np.arange(18.0).reshape(6, 3), np.tile([0.0, 0.0, 0.0, 1.0], (6, 1)))
    got = last_per_time(SampleChunk(times, ("a", "b"), positions, (track,)))
    assert got.times_ns.tolist() == [1, 2, 3]
    np.testing.assert_array_equal(got.positions, [[0.0, 0.0], [3.0, 2.0], [nan, 5.0]])
    np.testing.assert_array_equal(got.frames[0].translation, [[0, 1, 2], [9, 10, 11], [15, 16, 17]])
    unique = SampleChunk(np.array([1, 2], dtype=np.int64), ("a",), np.array([[1.0], [2.0]]))
    assert last_per_time(unique) is unique
