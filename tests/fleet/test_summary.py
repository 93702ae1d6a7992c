"""The fleet summary (issue 25): the maths on arrays worked out by hand, and the whole way — bags written by
rosbags (tests/fleetbags.py, whose docstring works out each value), converted by the real CLI, summed up through
a real catalog server — against those hand values."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from conftest import cli
from fleetbags import TURN, TURN_MESSAGES, WALK, WALK_MESSAGES, turn_bag, walk_bag

import r2d2_viz
from r2d2_viz.fleet.summary import base_travel, max_joint_speed, messages_per_type

S = 1_000_000_000
IDENT = np.array([[0.0, 0.0, 0.0, 1.0]])


def test_joint_speed_is_the_largest_step_over_its_time() -> None:
    times = np.array([0, S // 2, S, S, 3 * S])  # two rows at 1 s: the last stands (no division by zero)
    values = np.array([[0.0, 0.0], [0.5, -2.0], [9.0, 9.0], [0.6, -2.0], [0.6, -1.0]])
    # by hand: steps of 1 and 4 rad/s (b: 2 rad in 0.5 s), then 0.2 and 0, then 0 and 0.5 rad/s
    speed, joint = max_joint_speed(times, values, ["a", "b"])
    assert speed == pytest.approx(4.0) and joint == "b"
    assert max_joint_speed(times[:1], values[:1], ["a", "b"]) == (None, None)


def test_base_travel_composes_the_chain_up_to_the_tree_root() -> None:
    q90 = np.array([[0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)]])
    t = np.array([0, S, 2 * S])
    edges = [
        ("world", "map", np.zeros(0, np.int64), np.array([[5.0, 5.0, 5.0]]), q90),  # static: no effect on length
        ("map", "odom", t, np.zeros((3, 3)), np.vstack([IDENT, IDENT, q90])),  # turns 90° at 2 s
        ("odom", "base", t, np.array([[2.0, 0, 0], [2.0, 0, 0], [2.0, 0, 0]]), np.repeat(IDENT, 3, 0)),
        ("base", "arm", t, np.array([[9.0, 9, 9], [0, 0, 0], [1, 1, 1]]), np.repeat(IDENT, 3, 0)),  # below the base
    ]
    distance, base, fixed = base_travel(edges, {"base", "arm"})
    # by hand: base at (2,0,0) in odom; odom turns 90° → (0,2,0): one step of 2√2
    assert (base, fixed) == ("base", "world")
    assert distance == pytest.approx(2 * math.sqrt(2))
    assert base_travel(edges, set()) == (None, None, None)  # no robot: nothing to say
    assert base_travel([], {"base"}) == (0.0, "base", "base")


def test_messages_are_summed_per_drawn_type() -> None:
    topics = {"/a": ["sensor_msgs/msg/LaserScan", 2], "/b": ["sensor_msgs/msg/LaserScan", 3]}
    topics["/c"] = ["rcl_interfaces/msg/ParameterEvent", 7]  # no display draws it
    assert messages_per_type(topics) == {"messages_LaserScan": 5}


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("fleet")
    walk_bag(root / "walk")
    turn_bag(root / "turn", storage="sqlite3")
    result = cli("--bag", str(root / "walk"), str(root / "turn"), "--save-dir", str(root / "out"), "--jobs", "2")
    assert result.returncode == 0, result.stderr
    return root / "out"


def _check(rows: list[dict[str, object]]) -> None:
    by_bag = {r["bag"]: r for r in rows}
    assert set(by_bag) == {"walk", "turn"}
    for name, expected in (("walk", {**WALK, **WALK_MESSAGES}), ("turn", {**TURN, **TURN_MESSAGES})):
        row = by_bag[name]
        for key, value in expected.items():
            if isinstance(value, float):
                assert float(str(row[key])) == pytest.approx(value, rel=1e-5), (name, key)
            else:
                assert str(row[key]) == str(value), (name, key)


def test_the_summary_through_the_catalog_matches_the_hand_values(fleet: Path, tmp_path: Path) -> None:
    out = tmp_path / "fleet.csv"
    result = cli("--dataset", str(fleet), "--summary", str(out))
    assert result.returncode == 0, result.stderr
    with out.open() as f:
        _check(list(csv.DictReader(f)))
    result = cli("--dataset", str(fleet), "--summary", str(tmp_path / "fleet.parquet"))
    assert result.returncode == 0, result.stderr
    _check(pq.read_table(tmp_path / "fleet.parquet").to_pylist())


def test_the_printed_summary_and_the_python_api(fleet: Path) -> None:
    result = cli("--dataset", str(fleet), "--summary")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].split()[:4] == ["bag", "duration_s", "topics", "distance_m"]
    assert [line.split()[:4] for line in lines[1:]] == [
        ["turn", "0.800", "3", "1.414"],
        ["walk", "0.800", "5", "7.000"],
    ]
    _check(r2d2_viz.fleet_summary(fleet).to_pylist())


def test_a_bad_summary_target_is_one_line(fleet: Path, tmp_path: Path) -> None:
    result = cli("--dataset", str(fleet), "--summary", str(tmp_path / "fleet.xlsx"))
    assert result.returncode == 2 and "write a .csv or a .parquet" in result.stderr
    assert len(result.stderr.splitlines()) == 1 and not list(tmp_path.iterdir())
    result = cli("--dataset", str(tmp_path / "nowhere"), "--summary")
    assert result.returncode == 2 and "not a directory" in result.stderr


def test_a_fleet_of_what_archives_hold_is_summed_up(tmp_path: Path) -> None:
    """Issue 33, findings 2 and 5: a TF-only recording (no robot, no joint) gets empty cells instead of failing
    the summary; a .db3 bag under a folder named ``run #2`` and a bag folder without metadata.yaml get their topic
    counts (read by the app's own reader, as the conversion reads them)."""
    from bagmaker import T0, BagSpec, joint_state, storage_file, string, tf_message, write_bag

    from r2d2_viz.robot.model import default_urdf_path

    step = 100_000_000
    tf_only = BagSpec()
    for k in range(5):
        tf_only.add("/tf", T0 + k * step, tf_message([(T0 + k * step, "odom", "axis", (0.1 * k, 0, 0), (0, 0, 0, 1))]))
    joints = BagSpec().add("/robot_description", T0, string(default_urdf_path().read_text()))
    for k in range(10):  # swivel 0.1 rad per 0.1 s: 1 rad/s, by hand
        joints.add(
            "/joint_states", T0 + k * step, joint_state(T0 + k * step, ["swivel", "tilt", "periscope"], [0.1 * k, 0, 0])
        )
    write_bag(tmp_path / "tfonly", tf_only)
    (tmp_path / "run #2").mkdir()
    night = write_bag(tmp_path / "night", joints, storage="sqlite3").rename(tmp_path / "run #2" / "night")
    # (written elsewhere and moved: rosbags' own SQLite writer takes a '#' in the path as the URI's fragment)
    loose = write_bag(tmp_path / "loose", joints)
    (loose / "metadata.yaml").unlink()
    assert storage_file(loose).suffix == ".mcap"
    out = tmp_path / "out"
    result = cli("--bag", str(tmp_path / "tfonly"), str(night), str(loose), "--save-dir", str(out), "--jobs", "2")
    assert result.returncode == 0, result.stderr
    result = cli("--dataset", str(out), "--summary", str(tmp_path / "fleet.csv"))
    assert result.returncode == 0, result.stderr
    with (tmp_path / "fleet.csv").open() as f:
        rows = {r["bag"]: r for r in csv.DictReader(f)}
    assert set(rows) == {"tfonly", "night", "loose"}
    assert rows["tfonly"]["topics"] == "1" and rows["tfonly"]["messages_TFMessage"] == "5"
    assert rows["tfonly"]["max_joint_speed"] == "" and rows["tfonly"]["fastest_joint"] == ""
    assert rows["tfonly"]["distance_m"] == ""  # no robot: no base to follow
    for name in ("night", "loose"):
        assert rows[name]["topics"] == "2" and rows[name]["messages_JointState"] == "10", rows[name]
        assert float(rows[name]["max_joint_speed"]) == pytest.approx(1.0) and rows[name]["fastest_joint"] == "swivel"
