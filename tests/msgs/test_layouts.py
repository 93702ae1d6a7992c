"""CDR layouts against rosbags' own serializer: the offsets found must hold the numbers rosbags put there."""

from __future__ import annotations

import numpy as np
import pytest
from bagmaker import TS, joint_state, tf_message
from hypothesis import given, settings
from hypothesis import strategies as st
from msgs_build import T, header, pose, quat, vec

from r2d2_viz.msgs.layouts import joint_state_layout, odometry_pose, odometry_poses, tf_layout

names = st.lists(st.text(alphabet="abcxyz_0123456789é", min_size=1, max_size=9), min_size=0, max_size=6, unique=True)


def _stamp(rng: np.random.Generator) -> int:
    return int(rng.integers(0, 2**31 - 1)) * 10**9 + int(rng.integers(0, 10**9))


@settings(max_examples=60, deadline=None)
@given(names=names, frame=st.text(alphabet="abc/", max_size=7), seed=st.integers(0, 2**32 - 1))
def test_joint_state_offsets_hold_rosbags_positions(names, frame, seed) -> None:
    rng = np.random.default_rng(seed)
    position = rng.normal(size=len(names))
    stamp = _stamp(rng)
    data = joint_state(stamp, names, position, frame_id=frame)
    layout = joint_state_layout(data)
    assert layout.names == tuple(names) and layout.frame_id == frame and layout.count == len(names)
    values = np.frombuffer(data[layout.positions : layout.end], dtype="<f8")
    np.testing.assert_array_equal(values, position)  # bit-exact: the same doubles rosbags wrote
    sec, nsec = np.frombuffer(data[4:12], dtype="<i4")
    assert int(sec) * 10**9 + int(nsec) == stamp
    assert layout.matches(joint_state(stamp + 1, names, position + 1, frame_id=frame))


def test_a_layout_does_not_match_other_names_or_lengths() -> None:
    layout = joint_state_layout(joint_state(0, ["a", "b"], [1, 2]))
    assert not layout.matches(joint_state(0, ["a", "c"], [1, 2]))
    assert not layout.matches(joint_state(0, ["a", "b"], [1]))
    assert not layout.matches(joint_state(0, ["a", "b"], [1, 2], frame_id="x"))
    assert not layout.matches(joint_state(0, ["a", "b"], [1, 2])[:-12])  # too short for its positions


def test_mismatched_lengths_are_seen() -> None:
    layout = joint_state_layout(joint_state(0, ["a", "b", "c"], [1.0]))
    assert layout.count == 1 and len(layout.names) == 3


def test_big_endian_and_junk_are_refused() -> None:
    msg = TS.deserialize_cdr(joint_state(5, ["a"], [1.0]), "sensor_msgs/msg/JointState")
    big = bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/JointState", little_endian=False))
    for data in (big, b"", b"\x00\x01\x00\x00" + b"\xff" * 20, joint_state(0, ["a"], [1.0])[:17]):
        with pytest.raises(ValueError):
            joint_state_layout(data)


@settings(max_examples=40, deadline=None)
@given(
    frames=st.lists(st.tuples(st.text("abc_/", min_size=1, max_size=6), st.text("xyz", max_size=5)), max_size=4),
    seed=st.integers(0, 2**32 - 1),
)
def test_tf_offsets_hold_rosbags_transforms(frames, seed) -> None:
    rng = np.random.default_rng(seed)
    items = [(_stamp(rng), parent, child, rng.normal(size=3), rng.normal(size=4)) for parent, child in frames]
    data = tf_message(items)
    layout = tf_layout(data)
    assert layout.parents == tuple(p for p, _ in frames) and layout.children == tuple(c for _, c in frames)
    for (stamp, _, _, xyz, q), s, t in zip(items, layout.stamps, layout.translations, strict=True):
        sec, nsec = np.frombuffer(data[s : s + 8], dtype="<i4")
        assert int(sec) * 10**9 + int(nsec) == stamp
        np.testing.assert_array_equal(np.frombuffer(data[t : t + 56], dtype="<f8"), np.concatenate([xyz, q]))
    moved = tf_message([(s + 7, p, c, v + 1, q * 2) for s, p, c, v, q in items])
    assert layout.matches(moved)
    if frames:
        renamed = tf_message([(s, p + "x", c, v, q) for s, p, c, v, q in items])
        assert not layout.matches(renamed)


def test_an_empty_tf_message_matches_only_empty_ones() -> None:
    # found on the real Webots e-puck bag: an empty /tf_static message, then one with 58 transforms that decoded
    # as the empty layout (zero rows), so 58 static frames were lost
    empty = tf_layout(tf_message([]))
    q = np.array([0.0, 0.0, 0.0, 1.0])
    full = tf_message([(5, "base_link", f"led{k}", np.zeros(3), q) for k in range(58)])
    assert empty.matches(tf_message([])) and not empty.matches(full)
    one = tf_layout(tf_message([(5, "base_link", "led0", np.zeros(3), q)]))
    assert not one.matches(tf_message([(5, "base_link", "led0", np.zeros(3), q)] * 2))  # a longer message


def test_tf_decoder_keeps_the_transforms_after_an_empty_message() -> None:
    from r2d2_viz.sources.bag_tf import TfDecoder

    q = np.array([0.0, 0.0, 0.0, 1.0])
    messages = [(1, tf_message([])), (2, tf_message([(5, "a", f"b{k}", np.zeros(3), q) for k in range(3)]))]
    decoder = TfDecoder(lambda d, t: TS.deserialize_cdr(bytes(d), t), static=True, time="receive")
    assert decoder.decode(messages).children == ("b0", "b1", "b2")


def _odometry(frame: str, child: str, xyz: tuple[float, float, float], q: tuple[float, ...], *, le: bool = True):
    cov = np.zeros(36)
    msg = T("nav_msgs/msg/Odometry")(
        header=header(frame, 3, 4),
        child_frame_id=child,
        pose=T("geometry_msgs/msg/PoseWithCovariance")(pose=pose(*xyz, quat(*q)), covariance=cov),
        twist=T("geometry_msgs/msg/TwistWithCovariance")(
            twist=T("geometry_msgs/msg/Twist")(linear=vec(), angular=vec()), covariance=cov
        ),
    )
    return bytes(TS.serialize_cdr(msg, msg.__msgtype__, little_endian=le))


@pytest.mark.parametrize("le", [True, False], ids=["little-endian", "big-endian"])
@pytest.mark.parametrize("names", [("", ""), ("odom", "base_link"), ("o", "ab"), ("odom_x", "b" * 13)])
def test_the_pose_read_from_the_bytes_is_rosbags_reading(names: tuple[str, str], le: bool) -> None:
    data = _odometry(*names, (1.5, -2.25, 0.125), (0.1, 0.2, 0.3, 0.927), le=le)
    p = TS.deserialize_cdr(data, "nav_msgs/msg/Odometry").pose.pose
    expected = [p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y, p.orientation.z]
    assert odometry_pose(data).tolist() == [*expected, p.orientation.w]


def test_bytes_that_are_no_odometry_read_as_nan() -> None:
    good = _odometry("odom", "base_link", (1.0, 2.0, 3.0), (0, 0, 0, 1))
    for bad in (b"", b"\x00\x01\x00\x00garbage", good[:60], b"\x07\x07" + good[2:], b"\x00\x01\x00\x00" + b"\xff" * 80):
        assert np.isnan(odometry_pose(bad)).all()
    assert odometry_poses([good, b""]).shape == (2, 7)
