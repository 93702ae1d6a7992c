"""Motion generators against independent ports of the ROS nodes they imitate (tests/reference.py)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from reference import joint_state_publisher_delta, state_publisher

from r2d2_viz.errors import UsageError
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.robot.synth import random_urdf
from r2d2_viz.sources.motion import SWEEP_STEP, default_motion, make_motion


@pytest.fixture(scope="module")
def r2d2(tutorial_urdf: Path):
    return load_urdf(tutorial_urdf)


def _all(robot, name: str | None, n: int, chunk: int):
    """(sample times in ns, positions, odom → root translations and quaternions or None) of ``n`` samples."""
    motion = make_motion(robot, name, n_samples=n)
    chunks = list(motion.chunks(chunk))
    assert all(c.joints == motion.joints for c in chunks)
    positions = np.concatenate([c.positions for c in chunks])
    tracks = [c.frames for c in chunks]
    odom_t = np.concatenate([t[0].translation for t in tracks]) if tracks[0] else None
    odom_q = np.concatenate([t[0].quat_xyzw for t in tracks]) if tracks[0] else None
    return np.concatenate([c.times_ns for c in chunks]), positions, odom_t, odom_q


def test_tutorial_is_state_publisher_sample_for_sample(r2d2) -> None:
    n = 3 * 1440
    motion = make_motion(r2d2, "tutorial")
    assert motion.frames == (("odom", "axis"),) and motion.clock == "duration"
    times, positions, odom_t, odom_q = _all(r2d2, "tutorial", n, chunk=1000)
    reference = state_publisher(n)
    assert np.array_equal(times, np.rint(np.arange(n) * 1e9 / 30))  # sample k at k / 30 s
    for name in ("tilt", "periscope"):  # the bouncing state machine: identical floating-point sequence
        column = motion.joints.index(name)
        assert positions[:, column].tolist() == [r["joint_state"][name] for r in reference]
    swivel = positions[:, motion.joints.index("swivel")]
    assert np.allclose(swivel, [r["joint_state"]["swivel"] for r in reference], rtol=0, atol=1e-9)
    assert np.allclose(odom_t, [r["odom_translation"] for r in reference], rtol=0, atol=1e-9)
    assert np.allclose(odom_q, [r["odom_rotation_xyzw"] for r in reference], rtol=0, atol=1e-9)


def test_tutorial_published_ranges_and_lap(r2d2) -> None:
    motion = make_motion(r2d2, "tutorial")
    _, positions, odom_t, _ = _all(r2d2, "tutorial", 1441, chunk=100)
    tilt = positions[:, motion.joints.index("tilt")]
    periscope = positions[:, motion.joints.index("periscope")]
    # Ranges stated in the issue: tilt [−0.5061, +0.01745] (−29° … +1°), periscope [0, 0.2]
    assert tilt.min() == pytest.approx(-29 * math.pi / 180) and tilt.max() == pytest.approx(math.pi / 180)
    assert periscope.min() == pytest.approx(0, abs=1e-12) and periscope.max() == pytest.approx(0.2)
    # one lap = 1440 samples: sample 1440 is back at (2, 0, 0.7)
    assert np.allclose(odom_t[1440], [2, 0, 0.7], atol=1e-9) and not np.allclose(odom_t[720], [2, 0, 0.7])


def test_chunking_does_not_change_the_samples(r2d2) -> None:
    a = _all(r2d2, "tutorial", 500, chunk=7)
    b = _all(r2d2, "tutorial", 500, chunk=500)
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(x, y)


@pytest.mark.parametrize(
    ("joint_xml", "lower", "upper", "continuous"),
    [
        ('type="revolute"><limit lower="-0.3" upper="0.2" effort="1" velocity="1"/>', -0.3, 0.2, False),
        ('type="revolute"><limit lower="0.5" upper="1.5" effort="1" velocity="1"/>', 0.5, 1.5, False),  # 0 outside
        ('type="prismatic"><limit lower="-0.1" upper="0.05" effort="1" velocity="1"/>', -0.1, 0.05, False),
        ('type="continuous">', -math.pi, math.pi, True),
    ],
)
def test_sweep_is_joint_state_publisher_delta(tmp_path: Path, joint_xml: str, lower, upper, continuous) -> None:
    urdf = tmp_path / "one.urdf"
    urdf.write_text(
        f'<robot name="one"><link name="a"/><link name="b"/><joint name="j" {joint_xml}'
        '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint></robot>'
    )
    robot = load_urdf(urdf)
    assert default_motion(robot) == "sweep"
    n = 2000
    _, positions, odom_t, _ = _all(robot, None, n, chunk=333)
    expected = joint_state_publisher_delta(lower, upper, continuous=continuous, delta=SWEEP_STEP, n_samples=n)
    assert np.allclose(positions[:, 0], expected, rtol=0, atol=1e-9)
    assert odom_t is None  # the root stays at odom


def test_still_is_all_zeros_and_tutorial_needs_its_joints(r2d2, tmp_path: Path) -> None:
    _, positions, _, _ = _all(r2d2, "still", 10, chunk=4)
    assert positions.shape == (10, 3) and not positions.any()
    other = tmp_path / "other.urdf"
    other.write_text(random_urdf(6, seed=3))
    robot = load_urdf(other)
    with pytest.raises(UsageError, match="needs the joints swivel, tilt, periscope"):
        make_motion(robot, "tutorial")
    assert default_motion(r2d2) == "tutorial"


@pytest.mark.parametrize("bound", ["1e16", "1e300", "inf"])
def test_limits_that_mean_unlimited_sweep_like_a_continuous_joint(tmp_path: Path, bound: str) -> None:
    # example-robot-data's iris.urdf gives its rotors ±1e16: a sweep over that range would never end
    urdf = tmp_path / "wide.urdf"
    urdf.write_text(
        '<robot name="wide"><link name="a"/><link name="b"/><joint name="j" type="revolute">'
        f'<limit lower="-{bound}" upper="{bound}" effort="1" velocity="1"/>'
        '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint></robot>'
    )
    n = 1000
    _, positions, _, _ = _all(load_urdf(urdf), "sweep", n, chunk=400)
    expected = joint_state_publisher_delta(-math.pi, math.pi, continuous=True, delta=SWEEP_STEP, n_samples=n)
    assert np.allclose(positions[:, 0], expected, rtol=0, atol=1e-9)
