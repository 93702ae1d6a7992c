"""RViz's Odometry tolerance test (which poses its display keeps), held to RViz's C++ as transcribed in
tests/odombags.py, alone and through the real CLI on a bag rosbags wrote (stopped 15 s, then driving 11.2 m, then
turning in place), read back with Rerun's reader: the poses kept are RViz's and as worked out by hand; a replay's
windows, a live replay and one message at a time keep the same; an .rviz config's tolerances and Keep apply."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, cli
from odombags import DRIVING, RVIZ_KEEP, RVIZ_TOLERANCE, STEP, odometry, poses, rviz_kept, times, write_odometry_bag
from rrd import read_recording

from r2d2_viz.msgs.layouts import odometry_pose, odometry_poses
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.viewer.blocks.odometry_keep import (
    ANGLE_TOLERANCE,
    POSITION_TOLERANCE,
    OdometryKeep,
    Tolerance,
    angular_distance,
    kept,
)
from r2d2_viz.viewer.display_feed import KEEP

ODOM = "nav_msgs/msg/Odometry"


def test_the_defaults_are_rvizs() -> None:
    # odometry_display.cpp: FloatProperty("Position Tolerance", 0.1f), FloatProperty("Angle Tolerance", 0.1f),
    # IntProperty("Keep", 100)
    assert (POSITION_TOLERANCE, ANGLE_TOLERANCE) == RVIZ_TOLERANCE and Tolerance() == Tolerance(*RVIZ_TOLERANCE)
    assert KEEP["nav_msgs/msg/Odometry"] == RVIZ_KEEP


def test_a_pose_exactly_at_the_tolerance_is_kept() -> None:
    # RViz drops a pose only when its distance is < the tolerance: 0.5 m steps (exact in float) with a 0.5 m
    # tolerance keep every pose, 0.25 m steps every second one
    steps = np.zeros((6, 7))
    steps[:, 6] = 1.0
    steps[:, 0] = 0.5 * np.arange(6)
    assert kept(steps, None, Tolerance(0.5, 0.5))[0].tolist() == [True] * 6
    steps[:, 0] = 0.25 * np.arange(6)
    assert kept(steps, None, Tolerance(0.5, 0.5))[0].tolist() == [True, False, True, False, True, False]


def test_the_angle_is_rvizs_quaternion_distance() -> None:
    # by hand: two yaws 0.3 rad apart are 0.3 rad apart whatever the sign of the quaternion (q and -q are one
    # rotation); a half turn about x from the identity is pi
    a = [0.0, 0.0, math.sin(0.1), math.cos(0.1)]
    b = [0.0, 0.0, math.sin(0.25), math.cos(0.25)]
    assert angular_distance(np.array(a), np.array(b)) == pytest.approx(0.3, abs=1e-6)
    assert angular_distance(np.array(a), -np.array(b)) == pytest.approx(0.3, abs=1e-6)
    assert angular_distance(np.array([0.0, 0, 0, 1]), np.array([1.0, 0, 0, 0])) == pytest.approx(math.pi, abs=1e-6)


def test_a_stopping_then_driving_robot_keeps_rvizs_poses() -> None:
    """The poses of tests/odombags.py: by hand, RViz keeps the first stopped pose, every second one driving
    (80) and every second one turning (5): 86 of 320."""
    messages = [odometry(t, *p) for t, p in zip(times(), poses(), strict=True)]
    expected = rviz_kept(messages)  # RViz's C++, transcribed, on rosbags' reading
    assert len(expected) == 1 + 80 + 5 and expected[:3] == [0, 151, 153]
    mask, last = kept(odometry_poses(messages), None, Tolerance())
    assert np.flatnonzero(mask).tolist() == expected
    assert last is not None and last.tolist() == odometry_pose(messages[expected[-1]]).tolist()


@pytest.mark.parametrize("tolerance", [(0.1, 0.1), (0.05, 0.3), (0.4, 0.02), (0.0, 0.0)])
def test_random_walks_keep_what_rviz_keeps(tolerance: tuple[float, float]) -> None:
    rng = np.random.default_rng(44)
    xy = np.cumsum(rng.normal(0, 0.04, (400, 2)) * (rng.random((400, 1)) < 0.5), axis=0)  # moves and pauses
    yaw = np.cumsum(rng.normal(0, 0.05, 400))
    walk = enumerate(zip(xy, yaw, strict=True))
    messages = [odometry(1000 + k, float(x), float(y), float(a)) for k, ((x, y), a) in walk]
    expected = rviz_kept(messages, tolerance)
    poses_ = odometry_poses(messages)
    assert np.flatnonzero(kept(poses_, None, Tolerance(*tolerance))[0]).tolist() == expected
    # in windows of any size, each starting from the last pose kept before it: the same poses
    got, last, start = [], None, 0
    for size in rng.integers(1, 40, 100):
        mask, last = kept(poses_[start : start + size], last, Tolerance(*tolerance))
        got += (start + np.flatnonzero(mask)).tolist()
        start += size
    assert got == expected


def test_a_pose_rviz_finds_invalid_is_left_to_its_decoder_and_never_compared_against() -> None:
    p = np.array([[0, 0, 0, 0, 0, 0, 1], [np.nan, 0, 0, 0, 0, 0, 1], [0, 0, 0, 0, 0, 0, 2], [0.01, 0, 0, 0, 0, 0, 1]])
    mask, last = kept(p, None, Tolerance())
    assert mask.tolist() == [True, True, True, False] and last is not None and last.tolist() == p[0].tolist()


def _messages() -> list[TopicMessage]:
    return [TopicMessage(t, "/odom", ODOM, odometry(t, *p)) for t, p in zip(times(), poses(), strict=True)]


def _drawn(recording: dict) -> dict[int, tuple[int, float]]:
    """Time → (slot, arrow origin's x) of every arrow drawn on ``/odom/<k>``."""
    drawn = {}
    for entity, rows in recording.items():
        if entity.startswith("/odom/"):
            origins = rows.temporal.get("Arrows3D:origins", [])
            for t, origin in zip(rows.times, origins, strict=False):
                if origin is not None:
                    drawn[t] = (int(entity.rsplit("/", 1)[1]), origin[0][0])
    return dict(sorted(drawn.items()))


def _replay(tmp_path: Path, *extra: str) -> dict:
    bag = tmp_path / "odom_bag"
    if not bag.exists():
        write_odometry_bag(bag)
    out = tmp_path / f"run{len(list(tmp_path.glob('*.rrd')))}.rrd"
    result = cli("--bag", str(bag), "--save", str(out), *extra)
    assert result.returncode == 0, result.stderr
    return read_recording(out)


def test_a_robot_that_stops_leaves_one_arrow_and_its_path_keeps_rvizs(tmp_path: Path) -> None:
    messages = _messages()
    expected = rviz_kept([m.data for m in messages])  # RViz's C++, transcribed, on rosbags' reading
    assert len(expected) == 86  # by hand: 1 stopped, every second of 160 driving, every second of 10 turning
    drawn = _drawn(_replay(tmp_path))
    assert list(drawn) == [messages[i].time_ns for i in expected]
    assert [slot for slot, _ in drawn.values()] == list(range(86))  # the poses kept take the slots in turn
    xs = [x for _, x in drawn.values()]
    # the arrows cover the whole path, 0 to 11.2 m, as RViz's do (the last 100 messages covered 4.97 to 11.2 m)
    assert xs[0] < 0.001 and np.isclose(xs[-1], STEP * DRIVING) and sum(x < 0.01 for x in xs) == 1


def test_a_live_replay_and_a_message_at_a_time_keep_the_same_poses(tmp_path: Path) -> None:
    messages = _messages()
    at_once = OdometryKeep(lambda topic: Tolerance()).kept(messages)
    one_by_one = OdometryKeep(lambda topic: Tolerance())
    assert [m.time_ns for m in at_once] == [m.time_ns for m in messages if one_by_one.kept([m])]
    saved, live = _replay(tmp_path), _replay(tmp_path, "--realtime", "--speed", "25")
    assert _drawn(live) == _drawn(saved) and len(_drawn(saved)) == 86


CONFIG = """Visualization Manager:
  Global Options:
    Fixed Frame: odom
  Displays:
    - Class: rviz_default_plugins/Odometry
      Name: Odometry
      Enabled: true
      Topic:
        Value: /odom
      Position Tolerance: 1
      Angle Tolerance: 0.5
      Keep: 3
"""


def test_an_rviz_configs_tolerances_and_keep_apply(tmp_path: Path) -> None:
    config = tmp_path / "odom.rviz"
    config.write_text(CONFIG)
    messages = _messages()
    expected = rviz_kept([m.data for m in messages], (1.0, 0.5))
    # by hand: the first stopped pose, every 15th driving (1.05 m), the 9th turning (0.54 rad): 12 poses
    assert len(expected) == 12 and expected[1:3] == [149 + 15, 149 + 30]  # driving pose k is message 149 + k
    drawn = _drawn(_replay(tmp_path, "--rviz", str(config)))
    assert list(drawn) == [messages[i].time_ns for i in expected]
    assert [slot for slot, _ in drawn.values()] == [i % 3 for i in range(12)]  # Keep 3: round three slots


def test_the_real_e_pucks_odometry_keeps_rvizs_poses() -> None:
    """The Webots e-puck (tests/data/bags/real/webots_epuck): 780 poses over a 0.82 m path that ends stopped. RViz
    keeps 27 (the transcription, on rosbags' reading); the last 100 messages, drawn before, covered 1.1 mm."""
    from msgs_build import TS
    from rosbags.highlevel import AnyReader

    places = [REPO / "tests" / "data" / "bags" / "real" / "webots_epuck", REPO.parent / "shared" / "bags" / "real"]
    bag = next((p for p in (places[0], places[1] / "webots_epuck") if (p / "metadata.yaml").is_file()), None)
    if bag is None:
        pytest.skip("the third-party bag webots_epuck is not in this clone: tests/data/bags/real/README.md says how")
    with AnyReader([bag], default_typestore=TS) as reader:
        odom = [c for c in reader.connections if c.topic == "/odom"]
        datas = [bytes(raw) for _, _, raw in reader.messages(connections=odom)]
    expected = rviz_kept(datas)
    poses_ = odometry_poses(datas)
    assert np.flatnonzero(kept(poses_, None, Tolerance())[0]).tolist() == expected and len(expected) == 27
    path = np.linalg.norm(np.diff(poses_[expected, :3], axis=0), axis=1).sum()
    assert 0.8 < path < 0.82 and np.linalg.norm(np.diff(poses_[-100:, :3], axis=0), axis=1).sum() < 0.002
