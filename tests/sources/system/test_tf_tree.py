"""The TF tree of crafted bags: rates, edges and gaps held to rosbags' own reading of the bag (tests/tfbags.py), and
one crafted bag per problem tf2 users know, each named in one line with its frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from tfbags import MS, T0, S, bag, edge_every, point, rate_and_gap, reference_edges, reference_static, spec, static

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.system.tf_read import bag_tree
from r2d2_viz.sources.system.tf_tree import TfTree, analyse, tf_rows


def tree_of(path: Path) -> TfTree:
    with open_bag(path) as b:
        return bag_tree(b)


def about(tree: TfTree, frame: str) -> list[str]:
    return [p for p in tree.problems if p.startswith(f"frame {frame}:")]


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_rates_edges_and_gaps_agree_with_rosbags(tmp_path: Path, storage: str) -> None:
    rng = np.random.default_rng(7)
    s = spec()
    odom = T0 + np.cumsum(rng.uniform(40, 60, 200)).astype(np.int64) * MS  # ~20 Hz, jittered
    odom = np.r_[odom[:100], odom[110:]]  # a gap of ~0.5 s
    edge_every(s, "odom", "base_link", odom)
    edge_every(s, "/base_link", "wheel", T0 + np.arange(1, 99) * 100 * MS)  # 10 Hz, a leading '/' (tf2 drops it)
    static(s, [("base_link", "laser"), ("map", "odom")])
    path = bag(tmp_path / "b", s, storage)
    tree = tree_of(path)
    reference = reference_edges(path)
    got = {(e.parent, e.child): e for e in tree.edges}
    assert set(got) == set(reference) | reference_static(path)
    for edge, times in reference.items():
        rate, gap = rate_and_gap(times)
        assert got[edge].rate_hz == pytest.approx(rate, rel=1e-9) and got[edge].max_gap_s == pytest.approx(gap)
        assert got[edge].count == len(times) and not got[edge].static
    assert got["base_link", "laser"].static and got["map", "odom"].static
    assert tree.roots == ("map",) and tree.problems == ()


def test_a_child_with_two_parents_is_named_once(tmp_path: Path) -> None:
    s = spec()
    times = T0 + np.arange(20) * 100 * MS
    edge_every(s, "map", "odom", times)
    edge_every(s, "odom", "base_link", times)
    edge_every(s, "map", "base_link", times + 10 * MS)  # a second localiser publishing the same child
    tree = tree_of(bag(tmp_path / "b", s))
    assert len(tree.problems) == 1
    assert about(tree, "base_link") == ["frame base_link: 2 parents, map and odom (tf2 keeps whichever came last)"]


def test_a_loop_is_named_once_by_its_first_frame(tmp_path: Path) -> None:
    s = spec()
    times = T0 + np.arange(20) * 100 * MS
    edge_every(s, "map", "odom", times)
    for parent, child in (("a", "b"), ("b", "c"), ("c", "a")):
        edge_every(s, parent, child, times)
    tree = tree_of(bag(tmp_path / "b", s))
    assert tree.problems == ("frame a: in a loop: a → c → b → a (each the parent of the one before)",)


def test_two_roots_name_the_smaller_tree(tmp_path: Path) -> None:
    s = spec()
    times = T0 + np.arange(20) * 100 * MS
    edge_every(s, "map", "odom", times)
    edge_every(s, "odom", "base_link", times)
    static(s, [("robot2/odom", "robot2/base_link")])  # the second robot's tree, never joined to map
    tree = tree_of(bag(tmp_path / "b", s))
    assert tree.roots == ("map", "robot2/odom")
    assert tree.problems == ("frame robot2/odom: a second root: its tree of 2 frames is not connected to map's",)


def test_a_frame_that_stopped_is_stale(tmp_path: Path) -> None:
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(100) * 100 * MS)  # 10 s at 10 Hz
    edge_every(s, "odom", "base_link", T0 + np.arange(20) * 100 * MS)  # stops after 2 s: 8 s = 80 periods early
    tree = tree_of(bag(tmp_path / "b", s))
    assert len(tree.problems) == 1
    assert about(tree, "base_link")[0].startswith("frame base_link: stale: its transform from odom stopped 8 s")


def test_a_frame_no_transform_reaches(tmp_path: Path) -> None:
    s = spec()
    times = T0 + np.arange(20) * 100 * MS
    edge_every(s, "map", "odom", times)
    for t in times:
        s.add("/points", int(t), point(int(t), "camera_link"))
        s.add("/points", int(t), point(int(t), "/odom"))  # reached (tf2 drops the '/')
    tree = tree_of(bag(tmp_path / "b", s, "sqlite3"))
    assert tree.problems == ("frame camera_link: named in the headers of /points; no transform reaches it",)


def test_a_transform_older_than_the_messages_that_use_it(tmp_path: Path) -> None:
    s = spec()
    times = T0 + np.arange(50) * 100 * MS
    edge_every(s, "map", "odom", times)
    edge_every(s, "odom", "base_link", times, lag_ns=S // 2)  # stamped 0.5 s before it is sent
    for t in times[5:]:
        s.add("/points", int(t) + 5 * MS, point(int(t), "base_link"))  # stamped when measured, sent 5 ms later
    tree = tree_of(bag(tmp_path / "b", s))
    (line,) = tree.problems
    assert line.startswith(
        "frame base_link: transforms older than the messages that use it: /points stamped up to 0.5 s after the "
        "newest odom → base_link transform received by then (45 of 45 messages)"
    )


def test_a_few_late_messages_are_jitter() -> None:
    # the real e-puck bag: 1 of 792 /joint_states 60 ms ahead of odom → base_link at 49 Hz is not a problem
    t = np.arange(0, 10 * S, 20 * MS, dtype=np.int64)
    rows = tf_rows(["odom"] * len(t), ["base_link"] * len(t), t, t)
    from r2d2_viz.sources.system.tf_tree import HeaderRows

    late = np.zeros(len(t), np.int64)
    late[::20] = 100 * MS  # 5 % of them stamped 100 ms ahead
    headers = HeaderRows(("/js",), np.zeros(len(t), np.int32), np.array(["base_link"] * len(t), object), t + late, t)
    assert analyse(rows, [], headers).problems == ()
    late[::5] = 100 * MS  # 20 %: a publisher stamping late
    headers = HeaderRows(("/js",), np.zeros(len(t), np.int32), np.array(["base_link"] * len(t), object), t + late, t)
    assert analyse(rows, [], headers).problems[0].endswith("(100 of 500 messages)")


def test_messages_that_arrive_after_their_transforms_are_fine() -> None:
    t = np.arange(0, 10 * S, 100 * MS, dtype=np.int64)
    rows = tf_rows(["odom"] * len(t), ["base_link"] * len(t), t, t)
    from r2d2_viz.sources.system.tf_tree import HeaderRows

    headers = HeaderRows(
        ("/scan",), np.zeros(len(t), np.int32), np.array(["base_link"] * len(t), object), t - 30 * MS, t + 20 * MS
    )
    assert analyse(rows, [], headers).problems == ()


def test_an_edge_seen_once_has_no_rate() -> None:
    rows = tf_rows(["odom"], ["base_link"], np.array([5]), np.array([5]))
    edge = {(e.parent, e.child): e for e in analyse(rows, [("base_link", "laser")]).edges}["odom", "base_link"]
    assert edge.count == 1 and edge.rate_hz is None and edge.max_gap_s is None
