"""The frames a robot's description adds to the TF tree (what robot_state_publisher publishes and the replay draws),
and the namespaced TF topics a replay reads: bags written by rosbags, the printed tree of the real CLI held to the
URDF read by hand (which joints are fixed, which move) and to the rates of rosbags' reading of the bag (messages − 1
over the span of the receive times, the largest gap); the tutorial's R2D2 by hand from its URDF and
state_publisher.py (odom → axis, and the joint states, at 30 Hz)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from bagmaker import tf_message
from conftest import cli
from tfbags import (
    MS,
    POINT,
    ROVER,
    T0,
    bag,
    edge_every,
    point,
    rate_and_gap,
    receive_times,
    reference_edges,
    rover,
    spec,
)

from r2d2_viz.cli.command import main
from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import default_urdf_path, parse_urdf
from r2d2_viz.sources.base import SampleChunk
from r2d2_viz.sources.system.tf_robot import RobotFrames

LINE = re.compile(r"^\s*(\S+) ← (\S+): (.*)$")


def edges_of(text: str) -> dict[str, tuple[str, str]]:
    """child → (parent, what the line says of the edge), from the printed tree."""
    return {m[1]: (m[2], m[3]) for line in text.splitlines() if (m := LINE.match(line))}


def rate(words: str) -> tuple[float, float]:
    """The rate and largest gap a line prints (4 and 3 significant digits: compared within 0.5 %)."""
    hz, gap = re.fullmatch(r"([\d.e+-]+) Hz, largest gap ([\d.e+-]+) s", words).groups()  # type: ignore[union-attr]
    return float(hz), float(gap)


def problems(text: str) -> list[str]:
    lines = text.splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("problems"))
    return [line.strip() for line in lines[at + 1 :]] if lines[at] != "problems: none" else []


def test_a_scan_in_a_urdf_frame_is_reached_and_the_robot_frames_are_in_the_tree(tmp_path: Path) -> None:
    s = spec()
    rover(s, T0 + np.arange(31) * 100 * MS)  # joint states at 10 Hz for 3 s
    edge_every(s, "odom", "base_link", T0 + np.arange(61) * 50 * MS)  # the robot's odometry at 20 Hz
    edge_every(s, "base_link", "wheel2", T0 + np.arange(16) * 200 * MS)  # one URDF edge on /tf too, at 5 Hz
    for k in range(15):
        s.add("/points", T0 + k * 200 * MS, point(T0 + k * 200 * MS, "laser"))
    path = bag(tmp_path / "b", s)
    done = cli("--bag", str(path), "--tf-tree", str(tmp_path / "t.dot"))
    assert done.returncode == 0, done.stderr
    edges = edges_of(done.stdout)
    # by hand from ROVER: laser on a fixed joint (static); wheel moved by the joint states, wheel2 its mimic;
    # caster's joint is named by no joint state, so robot_state_publisher never publishes it
    assert set(edges) == {"base_link", "laser", "wheel", "wheel2"}
    assert edges["laser"] == ("base_link", "static")
    js = rate_and_gap(receive_times(path, "/joint_states"))
    assert edges["wheel"][0] == "base_link" and rate(edges["wheel"][1]) == pytest.approx(js, rel=5e-3)
    recorded = reference_edges(path)  # the recorded /tf wins over the description: what was published
    assert rate(edges["wheel2"][1]) == pytest.approx(rate_and_gap(recorded["base_link", "wheel2"]), rel=5e-3)
    assert rate(edges["base_link"][1]) == pytest.approx(rate_and_gap(recorded["odom", "base_link"]), rel=5e-3)
    assert problems(done.stdout) == []  # was: "frame laser: named in the headers of /points; no transform reaches it"
    dot = (tmp_path / "t.dot").read_text()
    assert '"base_link" -> "laser" [label="static", style=dashed];' in dot
    assert '"base_link" -> "wheel" [label="10 Hz\nlargest gap 0.1 s"];' in dot


def test_a_second_robot_on_its_own_tf_topics_is_in_the_tree(tmp_path: Path) -> None:
    s = spec()
    s.types |= {"/robot2/tf": s.types["/tf"], "/robot2/tf_static": s.types["/tf"], "/robot2/points": POINT}
    rover(s, T0 + np.arange(31) * 100 * MS, "/robot2")
    edge_every(s, "map", "base_footprint", T0 + np.arange(31) * 100 * MS)
    s.add("/robot2/tf_static", T0, tf_message([(T0, "map", "odom", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))]))
    for t in T0 + np.arange(21) * 50 * MS:  # robot2's odometry for 1 s of the bag's 3 s: then it stops
        s.add("/robot2/tf", int(t), tf_message([(int(t), "odom", "base_link", (1.0, 0.0, 0.0), (0, 0, 0, 1.0))]))
    for k in range(6):  # while its odometry comes
        s.add("/robot2/points", T0 + k * 200 * MS, point(T0 + k * 200 * MS, "robot2/laser"))
    path = bag(tmp_path / "b", s)
    done = cli("--bag", str(path), "--tf-tree")
    assert done.returncode == 0, done.stderr
    edges = edges_of(done.stdout)
    # docs/bags.md, convention (B): /robot2/tf's frames read as robot2/<frame>, but the shared map
    assert {c: p for c, (p, _) in edges.items()} == {
        "base_footprint": "map",
        "robot2/odom": "map",
        "robot2/base_link": "robot2/odom",
        "robot2/laser": "robot2/base_link",
        "robot2/wheel": "robot2/base_link",
        "robot2/wheel2": "robot2/base_link",
    }
    odom = rate_and_gap(receive_times(path, "/robot2/tf"))
    assert rate(edges["robot2/base_link"][1]) == pytest.approx(odom, rel=5e-3)
    assert rate(edges["robot2/wheel"][1]) == pytest.approx(
        rate_and_gap(receive_times(path, "/robot2/joint_states")), rel=5e-3
    )
    assert edges["robot2/odom"][1] == edges["robot2/laser"][1] == "static"
    # by hand: its last transform at 1 s, the bag's end at 3 s: 2 s, 40 periods of its 20 Hz
    assert problems(done.stdout) == [
        "frame robot2/base_link: stale: its transform from robot2/odom stopped 2 s before the end of the bag "
        "(40 periods of its 20 Hz)"
    ]


R2D2_TREE = [  # by hand: r2d2.urdf's joints, state_publisher.py's odom → axis and joint states at 30 Hz (1/30 s apart)
    "odom (root)",
    "  axis ← odom: 30 Hz, largest gap 0.0333 s",
    "    body ← axis: 30 Hz, largest gap 0.0333 s",  # tilt (revolute)
    "      head ← body: 30 Hz, largest gap 0.0333 s",  # swivel (continuous)
    "        rod ← head: 30 Hz, largest gap 0.0333 s",  # periscope (prismatic)
    "          box ← rod: static",  # boxconnect (fixed)
    "    leg1 ← axis: static",  # leg1connect
    "    leg2 ← axis: static",  # leg2connect
    "problems: none",
]


def test_the_tutorial_r2d2_tree_prints() -> None:
    done = cli("--tf-tree")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert (
        lines[0].startswith("TF tree of the tutorial's R2D2") and "8 frames, 4 dynamic and 3 static edges" in lines[0]
    )
    assert lines[1:] == R2D2_TREE


def test_the_tutorial_r2d2_tree_prints_from_urdf(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    copy = tmp_path / "r2d2.urdf"
    copy.write_bytes(default_urdf_path().read_bytes())
    assert main(["--urdf", str(copy), "--tf-tree", "--duration", "2"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert "r2d2.urdf" in out[0] and "over 1.97 s" in out[0] and out[1:] == R2D2_TREE  # 60 samples: 59/30 s


def test_the_apps_own_bag_has_no_problems(tmp_path: Path) -> None:
    lap = tmp_path / "lap.mcap"
    saved = cli("--save", str(lap), "--duration", "5")
    assert saved.returncode == 0, saved.stderr
    done = cli("--bag", str(lap), "--tf-tree")
    assert done.returncode == 0, done.stderr
    assert problems(done.stdout) == []  # was: "frame rod: a second root: its tree of 2 frames is not connected…"
    edges = edges_of(done.stdout)
    assert edges["axis"][0] == "odom" and edges["box"] == ("rod", "static")
    tf = rate_and_gap(reference_edges(lap)["odom", "axis"])
    js = rate_and_gap(receive_times(lap, "/joint_states"))
    assert rate(edges["axis"][1]) == pytest.approx(tf, rel=5e-3)
    for frame in ("body", "head", "rod"):
        assert rate(edges[frame][1]) == pytest.approx(js, rel=5e-3)


def test_rows_follow_the_joints_each_sample_gives() -> None:
    tree = compile_tree(parse_urdf(ROVER))
    frames = RobotFrames((tree,), (("odom", "base_link"),), skip=frozenset({("base_link", "wheel2")}))
    chunk = SampleChunk(np.array([10, 20, 30]), ("wheel_joint",), np.array([[0.0], [np.nan], [1.0]]))
    parents, children, times = frames.rows([chunk])
    got = sorted(zip(times.tolist(), parents.tolist(), children.tolist(), strict=True))
    # wheel at the two samples that give it (wheel2 left to the recorded TF, caster never given); the track always
    assert got == [
        (10, "base_link", "wheel"),
        (10, "odom", "base_link"),
        (20, "odom", "base_link"),
        (30, "base_link", "wheel"),
        (30, "odom", "base_link"),
    ]
    assert frames.static_edges() == [("base_link", "laser")]
