"""``r2d2-viz --bag BAG --tf-tree [FILE]`` and ``--ros --tf-tree``, in a subprocess as a user runs them; rates and
edges held to rosbags' own reading of the bag (tests/tfbags.py)."""

from __future__ import annotations

import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from rrd import read_recording
from tfbags import (
    MS,
    T0,
    bag,
    edge_every,
    point,
    rate_and_gap,
    real_bag,
    reference_edges,
    reference_static,
    spec,
    static,
)

EDGE = re.compile(r"^ *(\S.*) ← (\S.*): (static|(\S+) Hz, largest gap (\S+) s|.*no rate)$")


def parsed(stdout: str) -> dict[tuple[str, str], str]:
    """``(parent, child)`` → its words, from the printed tree."""
    return {(m[2], m[1]): m[3] for line in stdout.splitlines() if (m := EDGE.match(line))}


def crafted(tmp_path: Path) -> Path:
    s = spec()
    times = T0 + np.arange(30) * 100 * MS
    edge_every(s, "map", "odom", times)
    edge_every(s, "map", "base_link", times[:5])  # two parents; and stale (it stopped 2.5 s early)
    edge_every(s, "odom", "base_link", times)
    static(s, [("base_link", "laser"), ("robot2/odom", "robot2/base_link")])  # a second root
    for t in times:
        s.add("/points", int(t), point(int(t), "camera"))  # no transform reaches it
    return bag(tmp_path / "crafted", s)


def test_the_tree_and_each_problem_once(tmp_path: Path) -> None:
    path = crafted(tmp_path)
    done = cli("--bag", str(path), "--tf-tree")
    assert done.returncode == 0, done.stderr
    edges = parsed(done.stdout)
    assert set(edges) == set(reference_edges(path)) | reference_static(path)
    assert edges["base_link", "laser"] == "static" and edges["map", "odom"].startswith("10 Hz, largest gap 0.1 s")
    problems = [line.strip() for line in done.stdout.splitlines() if line.strip().startswith("frame ")]
    assert len(problems) == 4 and len(set(problems)) == 4
    assert [p.split(":")[0] for p in sorted(problems)] == [
        "frame base_link",
        "frame base_link",
        "frame camera",
        "frame robot2/odom",
    ]
    assert any("2 parents, map and odom" in p for p in problems) and any("stale" in p for p in problems)


def test_the_graph_as_dot_and_svg(tmp_path: Path) -> None:
    path = crafted(tmp_path)
    done = cli("--bag", str(path), "--tf-tree", str(tmp_path / "tree.dot"))
    assert done.returncode == 0, done.stderr
    dot = (tmp_path / "tree.dot").read_text()
    for parent, child in set(reference_edges(path)) | reference_static(path):
        assert f'"{parent}" -> "{child}"' in dot
    svg = cli("--bag", str(path), "--tf-tree", str(tmp_path / "tree.svg"))
    if shutil.which("dot") is None:
        assert svg.returncode == 2 and svg.stderr.count("\n") == 1 and "graphviz" in svg.stderr
        assert not (tmp_path / "tree.svg").exists() and not svg.stdout
    else:
        assert svg.returncode == 0 and "<svg" in (tmp_path / "tree.svg").read_text()


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--tf-tree", "--rate", "0"], "--rate must be a positive number of Hz"),  # the robot's tree: a motion
        (["--bag", "B", "--tf-tree", "t.png"], "unknown extension '.png'"),
        (["--bag", "missing", "--tf-tree"], "no such file"),
    ],
)
def test_bad_usage_is_one_line(tmp_path: Path, args: list[str], words: str) -> None:
    path = crafted(tmp_path)
    done = cli(*[str(path) if a == "B" else a for a in args], cwd=tmp_path)
    assert done.returncode == 2 and words in done.stderr and done.stderr.count("\n") == 1, done.stderr


def test_a_real_bag_every_edge_at_rosbags_rate() -> None:
    path = real_bag("webots_epuck")
    done = cli("--bag", str(path), "--tf-tree")
    assert done.returncode == 0, done.stderr
    edges = parsed(done.stdout)
    reference = reference_edges(path)
    assert set(edges) == set(reference) | reference_static(path)
    for edge, times in reference.items():
        rate, gap = rate_and_gap(times)
        m = EDGE.match(f"x ← y: {edges[edge]}")
        assert (
            m is not None
            and float(m[4]) == pytest.approx(rate, rel=0.05)
            and float(m[5]) == pytest.approx(gap, rel=0.01)
        )


def test_live_tree_of_a_dds_peer(tmp_path: Path) -> None:
    from sources.live import ros_node

    if (missing := ros_node.netns_missing()) is not None:
        ros_node.unavailable(missing)
    peer = Path(__file__).resolve().parents[1] / "sources" / "live" / "nodes" / "tf_peer.py"
    exe = str(Path(sys.executable).parent / "r2d2-viz")
    saved = tmp_path / "live.rrd"
    listen = f'"{exe}" --ros --tf-tree --duration 3 && "{exe}" --ros --tf-tree --duration 2 --save "{saved}"'
    # the peer outlives both runs however slowly they start (a loaded machine), and is ended when they are done
    script = f'"{sys.executable}" "{peer}" 60 & p=$!; sleep 1; {listen}; rc=$?; kill $p 2>/dev/null; exit $rc'
    done = ros_node.in_netns(["sh", "-c", script], timeout=180)
    assert done.returncode == 0, done.stderr
    assert "Warning" not in done.stderr, done.stderr
    graph = read_recording(saved)["/tf_tree"]  # the same peer, its TF graph in a recording
    assert len(graph.times) >= 2 and set(graph.temporal["GraphNodes:node_ids"][-1]) == {"odom", "base_link", "head"}
    edges = parsed(done.stdout)
    assert set(edges) == {("odom", "base_link"), ("base_link", "head")}, done.stdout
    # tf_peer.py writes both transforms in one message every 50 ms (a sleep after each write): just under 20 Hz
    rate = float(edges["odom", "base_link"].split()[0])
    assert 15 < rate <= 20.5, done.stdout
    assert "problems: none" in done.stdout


def test_a_graph_file_with_a_sink_is_refused(tmp_path: Path) -> None:
    path = crafted(tmp_path)
    done = cli("--bag", str(path), "--tf-tree", "--save", str(tmp_path / "o.mcap"))
    assert done.returncode == 2 and "a bag has no graph view" in done.stderr and done.stderr.count("\n") == 1
    assert not (tmp_path / "o.mcap").exists()
    done = cli("--bag", str(path), "--tf-tree", "t.dot", "--save", str(tmp_path / "o.rrd"), cwd=tmp_path)
    assert done.returncode == 2 and "give --tf-tree alone" in done.stderr and done.stderr.count("\n") == 1
    assert not (tmp_path / "o.rrd").exists() and not (tmp_path / "t.dot").exists()


def test_a_real_ros1_bag_of_two_turtles_at_rosbags_rate() -> None:
    # tests/data/bags/ros1: turtlesim's tf tutorial recorded by ROS 1's rosbag (two turtles and a carrot frame);
    # rosbags' own ROS 1 reader gives the reference
    path = Path(__file__).resolve().parents[1] / "data" / "bags" / "ros1" / "example-lz4.bag"
    done = cli("--bag", str(path), "--tf-tree")
    assert done.returncode == 0, done.stderr
    edges = parsed(done.stdout)
    reference = reference_edges(path)
    assert (
        set(edges)
        == set(reference) | reference_static(path)
        == {
            ("world", "turtle1"),
            ("world", "turtle2"),
            ("turtle1", "carrot"),
        }
    )
    for edge, times in reference.items():
        rate, gap = rate_and_gap(times)
        m = EDGE.match(f"x ← y: {edges[edge]}")
        assert m is not None and float(m[4]) == pytest.approx(rate, rel=0.05)
        assert float(m[5]) == pytest.approx(gap, rel=0.01)
    assert done.stdout.rstrip().endswith("problems: none")
