"""Bags replayed through the command line: bags written by rosbags (tests/bagmaker.py), read back from the
recording with Rerun's reader; poses against yourdfpy's forward kinematics of the bag's joint states."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from bagmaker import T0, BagSpec, joint_state, string, tf_message, write_bag
from conftest import REPO, cli
from rrd import frame_edges_at, pose_in, read_recording, tf_by_child

ARM = REPO / "examples" / "arm6.urdf"
ARM_JOINTS = ("base_yaw", "shoulder_pitch", "elbow", "wrist_pitch", "wrist_roll")
MS = 1_000_000
YAW_90 = (0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5))


def _arm_bag(path: Path, *, storage: str, n: int = 50, description: bool = True, bad_tf: bool = False) -> dict:
    """The arm: five joints at 50 Hz and the tool slide at 10 Hz (two publishers, subsets of the joints), the base
    driving along x in odom (/tf), a camera fixed on the base (/tf_static, not in the URDF)."""
    spec = BagSpec()
    if description:
        spec.add("/robot_description", T0, string(ARM.read_text()))
    spec.add("/tf_static", T0, tf_message([(T0, "base_link", "camera", (0.1, 0, 0.3), YAW_90)]))
    rng = np.random.default_rng(1)
    states = []
    for k in range(n):
        t = T0 + (k + 1) * 20 * MS
        q = rng.uniform(-1, 1, len(ARM_JOINTS))
        spec.add("/joint_states", t, joint_state(t, ARM_JOINTS, q))
        states.append((t, dict(zip(ARM_JOINTS, q, strict=True))))
        if k % 5 == 0:
            spec.add("/joint_states", t + MS, joint_state(t + MS, ["tool_slide"], [0.01 * (k % 4)]))
            states.append((t + MS, {"tool_slide": 0.01 * (k % 4)}))
        items = [(t, "odom", "base_link", (0.01 * k, 0, 0), (0, 0, 0, 1))]
        if bad_tf:  # robot_state_publisher would say shoulder is 0.1 m above base_link; 5 cm off
            items.append((t, "base_link", "shoulder", (0, 0, 0.15), (0, 0, 0, 1)))
        spec.add("/tf", t, tf_message(items))
    write_bag(path, spec, storage=storage)
    return {"states": states}


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bag_moves_the_robot_by_its_joint_states(tmp_path: Path, storage: str) -> None:
    bag = tmp_path / "arm_bag"
    made = _arm_bag(bag, storage=storage)
    out = tmp_path / "arm.rrd"
    result = cli("--bag", str(bag), "--save", str(out))
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    urdf = yourdfpy.URDF.load(str(ARM), load_meshes=False)
    held = dict.fromkeys((*ARM_JOINTS, "tool_slide"), 0.0)
    worst = 0.0
    for t, values in made["states"]:
        held.update(values)  # the others keep their last value, like robot_state_publisher
        urdf.update_cfg(held)
        edges = frame_edges_at(recording, t)
        k = (t - T0) // (20 * MS) - 1  # the latest /tf: x = 0.01 k, sent at T0 + (k + 1) · 20 ms
        T_odom_base = np.eye(4)
        T_odom_base[0, 3] = 0.01 * k
        for link in ("shoulder", "forearm", "tool"):
            expected = T_odom_base @ urdf.get_transform(frame_to=link, frame_from="base_link")
            worst = max(worst, float(np.abs(pose_in(edges, link, "odom") - expected).max()))
    assert worst < 1e-5
    # the camera, known only to the bag, hangs where /tf_static put it; the timeline holds the receive times
    camera = pose_in(frame_edges_at(recording, T0 + 20 * MS), "camera", "base_link")
    assert np.allclose(camera[:3, 3], [0.1, 0, 0.3], atol=1e-6)
    assert tf_by_child(recording)["shoulder"].times[0] == T0 + 20 * MS
    assert "/tf_axes/camera" in recording and "/robot/visual/forearm/0" in recording


def test_a_tf_only_bag_replays_its_frames(tmp_path: Path) -> None:
    bag = tmp_path / "tf_only"
    _arm_bag(bag, storage="mcap", description=False)
    spec_only_tf = tmp_path / "tf_only_no_states"
    spec = BagSpec()
    for k in range(30):
        t = T0 + k * 10 * MS
        spec.add("/tf", t, tf_message([(t, "map", "odom", (k * 0.1, 0, 0), (0, 0, 0, 1))]))
    write_bag(spec_only_tf, spec)
    out = tmp_path / "tf.rrd"
    result = cli("--bag", str(spec_only_tf), "--save", str(out))
    assert result.returncode == 0, result.stderr
    assert "TF-only replay" in result.stderr
    recording = read_recording(out)
    assert len(tf_by_child(recording)["odom"].times) == 30
    assert np.allclose(pose_in(frame_edges_at(recording, T0 + 290 * MS), "odom", "map")[:3, 3], [2.9, 0, 0])
    assert "/tf_axes/map" in recording and "/robot" not in {p.split("/")[1] for p in recording if p.count("/")}


def test_recorded_tf_that_disagrees_with_the_kinematics_is_reported_once(tmp_path: Path) -> None:
    bag = tmp_path / "bad_tf"
    _arm_bag(bag, storage="mcap", bad_tf=True)
    result = cli("--bag", str(bag), "--save", str(tmp_path / "x.rrd"))
    assert result.returncode == 0, result.stderr
    assert result.stderr.count("disagrees with the kinematics") == 1
    assert "50 mm" in result.stderr


@pytest.mark.parametrize(
    ("make", "problem"),
    [
        (lambda p: p.mkdir(), "metadata.yaml"),
        (lambda p: (p.mkdir(), (p / "bag_0.db3").write_bytes(b"junk" * 1024)), "cannot read this bag"),
        (lambda p: p.with_suffix(".mcap").write_bytes(b"not a bag at all"), ""),
        (lambda p: None, "no such file or directory"),
    ],
)
def test_bad_bags_are_one_line_and_exit_2(tmp_path: Path, make, problem: str) -> None:
    target = tmp_path / "bag"
    make(target)
    path = target.with_suffix(".mcap") if target.with_suffix(".mcap").exists() else target
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(path), "--save", str(out))
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in result.stderr
    assert problem in lines[0] and not out.exists() and not list(tmp_path.glob(".out.rrd*"))


def test_a_wrong_type_on_joint_states_is_refused(tmp_path: Path) -> None:
    spec = BagSpec(types={"/joint_states": "std_msgs/msg/String"})
    spec.add("/joint_states", T0, string("hello"))
    write_bag(tmp_path / "wrong", spec)
    result = cli("--bag", str(tmp_path / "wrong"), "--urdf", str(ARM), "--save", str(tmp_path / "o.rrd"))
    assert result.returncode == 2 and "/joint_states" in result.stderr and "Traceback" not in result.stderr


def test_live_replay_is_paced_at_the_speed_asked(tmp_path: Path) -> None:
    bag = tmp_path / "arm_bag"
    _arm_bag(bag, storage="mcap", n=100)  # 2 s of joint states
    out = tmp_path / "live.rrd"
    exe = Path(sys.executable).parent / "r2d2-viz"
    start = time.monotonic()
    result = subprocess.run(
        [str(exe), "--bag", str(bag), "--save", str(out), "--realtime", "--speed", "4"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    elapsed = time.monotonic() - start
    assert result.returncode == 0, result.stderr
    assert elapsed >= 2.0 / 4 * 0.95  # the last joint state is due 1.98 s / 4 after the first
    recording = read_recording(out)
    assert len(tf_by_child(recording)["shoulder"].times) == 120  # 100 arm messages, 20 tool slide messages
