"""/tf and /tf_static as transform rows, on bags written by rosbags: values bit-exact to what rosbags serialized.
/tf comes through the bag's one pass (sources/playback.BagPass), /tf_static through the run's plan (read before the
first frame: sources/plan.plan_bag)."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
from bagmaker import T0, TS, BagSpec, string, tf_message, write_bag

from r2d2_viz.sources.bag_joints import TimeSource
from r2d2_viz.sources.bag_tf import concatenate
from r2d2_viz.sources.bags.bag import Bag, open_bag
from r2d2_viz.sources.base import TfRecords
from r2d2_viz.sources.plan import plan_bag
from r2d2_viz.sources.playback import BagPass, Segment

ROBOT = "<robot name='r'><link name='base_link'/></robot>"


def _moving(bag: Bag, time: TimeSource = "receive", segments: list[Segment] | None = None) -> list[TfRecords]:
    """/tf as the pass hands it on, window by window."""
    segments = segments or [Segment(("/tf",))]
    return [w.tf for w in BagPass(bag, segments, actuated=None, displays={}, time=time).windows(1000) if w.tf]


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
        static = plan_bag(bag).static_tf
        moving = concatenate(_moving(bag))
        stamped = concatenate(_moving(bag, "header"))
    assert static is not None and moving is not None and stamped is not None
    assert static.static and static.parents == ("base_link",) and static.children == ("camera",)
    np.testing.assert_array_equal(static.translation, [[0.1, 0, 0.3]])
    assert not moving.static and len(moving) == len(expected)
    assert moving.times_ns.tolist() == [e[0] for e in expected]
    assert stamped.times_ns.tolist() == [e[1] for e in expected]
    assert moving.parents == tuple(e[2] for e in expected) and moving.children == tuple(e[3] for e in expected)
    np.testing.assert_array_equal(moving.translation, [e[4] for e in expected])
    np.testing.assert_array_equal(moving.quat_xyzw, [e[5] for e in expected])


def test_bag_without_tf(tmp_path: Path) -> None:
    with open_bag(write_bag(tmp_path / "b", BagSpec().add("/robot_description", T0, string(ROBOT)))) as bag:
        plan = plan_bag(bag)
        assert plan.static_tf is None and plan.moving_tf is None
        assert _moving(bag) == []


def test_stretches_and_the_generic_path(tmp_path: Path) -> None:
    """Read in stretches, the same rows as whole; a big-endian message (rosbags' deserializer) among them; a
    message that cannot be decoded skipped with one warning per pass."""
    spec = BagSpec()
    for k in range(25):
        spec.add("/tf", T0 + k, tf_message([(T0 + k, "odom", "base_link", (k, 0, 0), (0, 0, 0, 1))]))
    msg = TS.deserialize_cdr(tf_message([(T0, "map", "odom", (1, 2, 3), (0, 0, 1, 0))]), "tf2_msgs/msg/TFMessage")
    spec.add("/tf", T0 + 30, bytes(TS.serialize_cdr(msg, "tf2_msgs/msg/TFMessage", little_endian=False)))
    spec.add("/tf", T0 + 31, b"\x00\x01\x00\x00\xff\xff")
    warnings: list[str] = []
    edges = [*range(0, 25, 4), 32]  # [0, 4), [4, 8) … [20, 24), [24, 32)
    stretches = [Segment(("/tf",), T0 + a, T0 + b) for a, b in itertools.pairwise(edges)]
    with open_bag(write_bag(tmp_path / "b", spec), warn=warnings.append) as bag:
        chunks = _moving(bag, segments=stretches)
        (whole,) = _moving(bag)
    assert sum(len(c) for c in chunks) == 26  # the stretches' windows together: every row once
    assert sum((c.children for c in chunks), ()) == whole.children == ("base_link",) * 25 + ("odom",)
    np.testing.assert_array_equal(np.vstack([c.translation for c in chunks]), whole.translation)
    np.testing.assert_array_equal(whole.translation[-1], [1, 2, 3])
    np.testing.assert_array_equal(whole.quat_xyzw[-1], [0, 0, 1, 0])
    assert whole.times_ns.tolist() == [T0 + k for k in range(25)] + [T0 + 30]
    assert warnings == [f"{tmp_path / 'b'}: /tf: skipped 1 messages that cannot be decoded"] * 2
