"""/tf and /tf_static as transform rows, on bags written by rosbags: values bit-exact to what rosbags serialized."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from bagmaker import T0, TS, BagSpec, string, tf_message, write_bag

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.bag_tf import read_tf, tf_chunks


def test_tf_and_tf_static_as_columns(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    spec = BagSpec().add("/tf_static", T0, tf_message([(T0 - 5, "base_link", "camera", (0.1, 0, 0.3), (0, 0, 0, 1))]))
    expected = []
    for k in range(40):
        t = T0 + k * 10**7
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        items = [(t - 7, "odom", "base_link", rng.normal(size=3), q)]
        if k % 2:
            items.append((t - 3, "map", "odom", (k, 0, 0), (0, 0, 0, 1)))
        spec.add("/tf", t, tf_message(items))
        expected += [(t, s, p, c, np.asarray(v, float), np.asarray(qq, float)) for s, p, c, v, qq in items]
    with open_bag(write_bag(tmp_path / "b", spec)) as bag:
        static, moving = read_tf(bag)
        stamped = read_tf(bag, time="header")[1]
    assert static.static and static.parents == ("base_link",) and static.children == ("camera",)
    np.testing.assert_array_equal(static.translation, [[0.1, 0, 0.3]])
    assert not moving.static and len(moving) == len(expected)
    assert moving.times_ns.tolist() == [e[0] for e in expected]
    assert stamped.times_ns.tolist() == [e[1] for e in expected]
    assert moving.parents == tuple(e[2] for e in expected) and moving.children == tuple(e[3] for e in expected)
    np.testing.assert_array_equal(moving.translation, [e[4] for e in expected])
    np.testing.assert_array_equal(moving.quat_xyzw, [e[5] for e in expected])


def test_bag_without_tf(tmp_path: Path) -> None:
    with open_bag(write_bag(tmp_path / "b", BagSpec().add("/robot_description", T0, string("x")))) as bag:
        assert read_tf(bag) == []


def test_chunks_and_the_generic_path(tmp_path: Path) -> None:
    """In chunks, the same rows as whole; a big-endian message (rosbags' deserializer) among them; a message
    that cannot be decoded skipped with one warning."""
    spec = BagSpec()
    for k in range(25):
        spec.add("/tf", T0 + k, tf_message([(T0 + k, "odom", "base_link", (k, 0, 0), (0, 0, 0, 1))]))
    msg = TS.deserialize_cdr(tf_message([(T0, "map", "odom", (1, 2, 3), (0, 0, 1, 0))]), "tf2_msgs/msg/TFMessage")
    spec.add("/tf", T0 + 30, bytes(TS.serialize_cdr(msg, "tf2_msgs/msg/TFMessage", little_endian=False)))
    spec.add("/tf", T0 + 31, b"\x00\x01\x00\x00\xff\xff")
    warnings: list[str] = []
    with open_bag(write_bag(tmp_path / "b", spec), warn=warnings.append) as bag:
        chunks = list(tf_chunks(bag, "/tf", max_messages=4))
        (whole,) = read_tf(bag)
    assert [len(c) for c in chunks] == [4] * 6 + [2]
    assert sum((c.children for c in chunks), ()) == whole.children == ("base_link",) * 25 + ("odom",)
    np.testing.assert_array_equal(np.vstack([c.translation for c in chunks]), whole.translation)
    np.testing.assert_array_equal(whole.translation[-1], [1, 2, 3])
    np.testing.assert_array_equal(whole.quat_xyzw[-1], [0, 0, 1, 0])
    assert whole.times_ns.tolist() == [T0 + k for k in range(25)] + [T0 + 30]
    assert warnings == [f"{tmp_path / 'b'}: /tf: skipped 1 messages that cannot be decoded"] * 2
