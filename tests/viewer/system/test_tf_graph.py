"""The TF graph view's data (``/tf_tree``), read back with Rerun's reader: every frame a node, every parent → child
an edge, labels with the rate over the last 2 s and the age at each snapshot (held to rates computed by hand or
from rosbags' reading of the bag), stale frames red; and the layout with its graph view."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from conftest import cli
from rrd import blueprint_components, read_recording
from tfbags import (
    MS,
    T0,
    S,
    bag,
    edge_every,
    point,
    receive_times,
    reference_edges,
    reference_static,
    rover,
    spec,
    static,
)

from r2d2_viz.sources.base import TfRecords
from r2d2_viz.viewer.system.tf_graph import FRESH_COLOR, STALE_COLOR, STATIC_COLOR, TfGraph, _layout


def records(times, parents, children, *, static: bool = False) -> TfRecords:
    n = len(times)
    return TfRecords(
        np.asarray(times, np.int64),
        tuple(parents),
        tuple(children),
        np.zeros((n, 3)),
        np.tile([0, 0, 0, 1.0], (n, 1)),
        static,
    )


def snapshot(rows, i: int) -> dict[str, tuple[str, int]]:
    """Frame → (label, colour) at snapshot ``i``."""
    ids, labels, colors = (rows.temporal[f"GraphNodes:{k}"][i] for k in ("node_ids", "labels", "colors"))
    return {n: (label, c) for n, label, c in zip(ids, labels, colors, strict=True)}


def test_rates_ages_and_stale_frames_at_each_snapshot(tmp_path: Path) -> None:
    out = tmp_path / "g.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    graph = TfGraph(rec, clock="timestamp")
    graph.add(records([T0], ["base_link"], ["laser"], static=True))
    t = T0 + np.arange(60) * 100 * MS  # 6 s of odom → base_link at 10 Hz, in two feeds
    w = T0 + np.arange(10) * 50 * MS  # base_link → wheel at 20 Hz for 0.5 s, then never again
    graph.add(records(np.r_[t[:25], w], ["odom"] * 25 + ["base_link"] * 10, ["base_link"] * 25 + ["wheel"] * 10))
    graph.add(records(t[25:], ["odom"] * 35, ["base_link"] * 35))
    rec.flush()
    rec.disconnect()
    rows = read_recording(out)["/tf_tree"]
    assert rows.times == [T0, *range(T0, T0 + 6 * S, S // 2)]  # the static one, then every half second
    at_3s = snapshot(rows, rows.times.index(T0 + 3 * S, 1))
    # by hand: at 3 s, the 2 s window (1 s, 3 s] holds 20 odom messages → 10 Hz, the last one at 3 s → age 0
    assert at_3s["base_link"] == ("base_link\n10 Hz · 0 s", FRESH_COLOR)
    # wheel: 10 messages from 0 to 0.45 s, none in the window: stale, 2.55 s old; its rate over the window 0
    assert at_3s["wheel"] == ("wheel\n0 Hz · 2.5 s", STALE_COLOR)
    assert at_3s["laser"] == ("laser\nstatic", STATIC_COLOR) and at_3s["odom"][0] == "odom"
    at_0_5 = snapshot(rows, rows.times.index(T0 + S // 2, 1))
    # at 0.5 s: 9 wheel messages after its first, over the 0.5 s since it came → 18 Hz; the last at 0.45 s
    assert at_0_5["wheel"] == ("wheel\n18 Hz · 0.05 s", FRESH_COLOR)
    edges = rows.temporal["GraphEdges:edges"][-1]
    assert {(e["first"], e["second"]) for e in edges} == {
        ("base_link", "laser"),
        ("odom", "base_link"),
        ("base_link", "wheel"),
    }
    assert graph.snapshots == 13


def test_layout_left_to_right() -> None:
    frames, positions, roots = _layout([("map", "odom"), ("odom", "base"), ("base", "a"), ("base", "b"), ("x", "y")])
    at = {f: tuple(p) for f, p in zip(frames, positions, strict=True)}
    assert roots == {"map", "x"} and set(frames) == {"map", "odom", "base", "a", "b", "x", "y"}
    assert at["map"][0] < at["odom"][0] < at["base"][0] < at["a"][0] == at["b"][0]  # depth across
    assert at["a"][1] < at["b"][1] and at["base"][1] == (at["a"][1] + at["b"][1]) / 2  # siblings down, parent between
    assert at["y"][1] > at["b"][1]  # the second tree below the first


def test_a_saved_bag_has_the_graph_beside_the_3d_view(tmp_path: Path) -> None:
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(50) * 100 * MS)  # 5 s at 10 Hz
    edge_every(s, "odom", "base_link", T0 + np.arange(40) * 50 * MS)  # 2 s at 20 Hz, then it stops
    static(s, [("base_link", "laser")])
    path = bag(tmp_path / "b", s)
    out = tmp_path / "b.rrd"
    done = cli("--bag", str(path), "--tf-tree", "--save", str(out))
    assert done.returncode == 0, done.stderr
    rows = read_recording(out)["/tf_tree"]
    reference = reference_edges(path)
    edges = {(e["first"], e["second"]) for e in rows.temporal["GraphEdges:edges"][-1]}
    assert edges == set(reference) | reference_static(path)
    assert set(rows.temporal["GraphNodes:node_ids"][-1]) == {f for e in edges for f in e}
    # the rate of map → odom at 4 s, from rosbags' receive times: messages in the last 2 s over 2 s
    times = np.array(reference["map", "odom"])
    expected = np.count_nonzero((times > T0 + 2 * S) & (times <= T0 + 4 * S)) / 2.0
    label = snapshot(rows, rows.times.index(T0 + 4 * S))["odom"][0]
    assert float(label.split("\n")[1].split(" Hz")[0]) == pytest.approx(expected, rel=0.05)
    assert snapshot(rows, rows.times.index(T0 + 4 * S))["base_link"][1] == STALE_COLOR  # stopped 2 s before
    assert snapshot(rows, rows.times.index(T0 + 1 * S))["base_link"][1] == FRESH_COLOR
    views = blueprint_components(out)
    graph = [v for v in views.values() if v.get("ViewBlueprint:class_identifier") == ["Graph"]]
    assert len(graph) == 1 and graph[0]["ViewBlueprint:space_origin"] == ["/tf_tree"]
    contents = [v for v in views.values() if "ViewContents:query" in v and "+ /**" in v["ViewContents:query"]]
    assert all("- /tf_tree/**" in v["ViewContents:query"] for v in contents)  # not drawn in the 3D view


def test_without_the_flag_no_graph(tmp_path: Path) -> None:
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(20) * 100 * MS)
    out = tmp_path / "b.rrd"
    done = cli("--bag", str(bag(tmp_path / "b", s)), "--save", str(out))
    assert done.returncode == 0, done.stderr
    assert "/tf_tree" not in read_recording(out)
    assert not [v for v in blueprint_components(out).values() if v.get("ViewBlueprint:class_identifier") == ["Graph"]]


def test_an_edge_on_tf_and_tf_static_is_dynamic_from_its_first_tf_message(tmp_path: Path) -> None:
    out = tmp_path / "g.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    graph = TfGraph(rec, clock="timestamp")
    graph.add(records([T0], ["odom"], ["base_link"], static=True))
    graph.add(records(T0 + np.arange(30) * 100 * MS, ["odom"] * 30, ["base_link"] * 30))  # then on /tf at 10 Hz
    rec.flush()
    rec.disconnect()
    rows = read_recording(out)["/tf_tree"]
    # as the printed tree and docs/system.md count it: dynamic (by hand: 20 messages in the 2 s before 2 s, the last
    # at 2 s); the graph said "static" for the whole run
    assert snapshot(rows, rows.times.index(T0 + 2 * S, 1))["base_link"] == ("base_link\n10 Hz · 0 s", FRESH_COLOR)
    assert snapshot(rows, 0)["base_link"] == ("base_link\nstatic", STATIC_COLOR)  # before it came on /tf


def test_the_robot_frames_are_in_the_graph(tmp_path: Path) -> None:
    s = spec()
    rover(s, T0 + np.arange(31) * 100 * MS)  # joint states at 10 Hz for 3 s
    edge_every(s, "odom", "base_link", T0 + np.arange(61) * 50 * MS)
    path = bag(tmp_path / "b", s)
    out = tmp_path / "b.rrd"
    done = cli("--bag", str(path), "--tf-tree", "--save", str(out))
    assert done.returncode == 0, done.stderr
    rows = read_recording(out)["/tf_tree"]
    edges = {(e["first"], e["second"]) for e in rows.temporal["GraphEdges:edges"][-1]}
    # by hand from ROVER: laser fixed, wheel and its mimic wheel2 moved by the joint states (caster never named)
    assert edges == {("odom", "base_link"), ("base_link", "laser"), ("base_link", "wheel"), ("base_link", "wheel2")}
    at_2s = snapshot(rows, rows.times.index(T0 + 2 * S))
    times = np.array(receive_times(path, "/joint_states"))  # rosbags: joint states in the 2 s window, over 2 s
    expected = np.count_nonzero((times > T0) & (times <= T0 + 2 * S)) / 2.0
    assert at_2s["wheel"] == (f"wheel\n{expected:.3g} Hz · 0 s", FRESH_COLOR) and at_2s["wheel2"][0].endswith(" · 0 s")
    assert at_2s["laser"] == ("laser\nstatic", STATIC_COLOR)


def test_the_tutorial_robot_has_its_graph(tmp_path: Path) -> None:
    out = tmp_path / "r2d2.rrd"
    done = cli("--tf-tree", "--save", str(out), "--duration", "2")
    assert done.returncode == 0, done.stderr
    rows = read_recording(out)["/tf_tree"]
    edges = {(e["first"], e["second"]) for e in rows.temporal["GraphEdges:edges"][-1]}
    # by hand: r2d2.urdf's six joints and state_publisher.py's odom → axis
    assert edges == {
        ("odom", "axis"),
        ("axis", "leg1"),
        ("axis", "leg2"),
        ("axis", "body"),
        ("body", "head"),
        ("head", "rod"),
        ("rod", "box"),
    }


def test_snapshots_go_on_after_the_transforms_stop(tmp_path: Path) -> None:
    """odom → base_link at 10 Hz from 0 to 2.9 s, then nothing while the run goes on to 7 s (:meth:`advance`, as a
    replay's windows end). By hand, with the printed tree's rule (stale: older than 5 of its average periods, 0.5 s,
    and 0.5 s): at 3 s the window (1 s, 3 s] holds 19 → 9.5 Hz, 0.1 s old, green; at 3.5 s 14 → 7 Hz, 0.6 s old:
    red (the rate over the window would have allowed 5 / 7 Hz = 0.71 s); at 7 s none, 4.1 s old, red. Advancing to
    where the graph's clock and the run's disagree beyond the horizon logs nothing."""
    out = tmp_path / "g.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    graph = TfGraph(rec, clock="timestamp", horizon_ns=10 * S)
    graph.advance(T0)  # nothing moves yet: no snapshot
    graph.add(records(T0 + np.arange(30) * 100 * MS, ["odom"] * 30, ["base_link"] * 30))
    graph.advance(T0 + 5 * S)
    graph.advance(T0 + 7 * S)
    graph.advance(T0 + 60 * S)  # 57 s past the newest transform, beyond the 10 s horizon
    rec.flush()
    rec.disconnect()
    rows = read_recording(out)["/tf_tree"]
    assert rows.times == list(range(T0, T0 + 7 * S + 1, S // 2))
    assert snapshot(rows, rows.times.index(T0 + 3 * S))["base_link"] == ("base_link\n9.5 Hz · 0.1 s", FRESH_COLOR)
    assert snapshot(rows, rows.times.index(T0 + 7 * S // 2))["base_link"] == ("base_link\n7 Hz · 0.6 s", STALE_COLOR)
    assert snapshot(rows, rows.times.index(T0 + 7 * S))["base_link"] == ("base_link\n0 Hz · 4.1 s", STALE_COLOR)


def test_a_bag_whose_tf_stops_while_it_goes_on(tmp_path: Path) -> None:
    """A saved replay: /tf at 10 Hz to 3.9 s, /points to 10 s. The graph gets a snapshot every half second to the
    bag's end (it stopped at 3.5 s with the last transform, "10 Hz · 0 s" in green for the rest of the bag); at the
    end odom's frame is red, 6.1 s old (by hand), as the printed tree says it stale, 6.1 s before the end."""
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(40) * 100 * MS)
    for k in range(101):
        s.add("/points", T0 + k * 100 * MS, point(T0, "odom"))
    path = bag(tmp_path / "b", s)
    out = tmp_path / "g.rrd"
    done = cli("--bag", str(path), "--tf-tree", "--save", str(out))
    assert done.returncode == 0, done.stderr
    rows = read_recording(out)["/tf_tree"]
    assert rows.times == list(range(T0, T0 + 10 * S + 1, S // 2))
    assert snapshot(rows, len(rows.times) - 1)["odom"] == ("odom\n0 Hz · 6.1 s", STALE_COLOR)
    assert snapshot(rows, rows.times.index(T0 + 4 * S))["odom"] == ("odom\n9.5 Hz · 0.1 s", FRESH_COLOR)
    printed = cli("--bag", str(path), "--tf-tree")
    assert "frame odom: stale: its transform from map stopped 6.1 s before the end of the bag" in printed.stdout
