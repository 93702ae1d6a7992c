"""The Python API for Rerun users, and examples/log_trajectory.py: a robot that is not the R2D2 (a six-joint
arm, examples/arm6.urdf) logged into the user's own recording; poses through the recording's named frames
against yourdfpy's forward kinematics; the same entities as the command line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import rerun as rr
import yourdfpy
from conftest import REPO, cli
from rrd import frame_edges_at, pose_in, read_recording

import r2d2_viz
from r2d2_viz.errors import UsageError

ARM = REPO / "examples" / "arm6.urdf"


def _worst(recording, urdf: Path, times_ns, configs, root=None) -> float:
    model = yourdfpy.URDF.load(str(urdf), load_meshes=False)
    worst = 0.0
    for k, (t, cfg) in enumerate(zip(times_ns, configs, strict=True)):
        model.update_cfg(cfg)
        edges = frame_edges_at(recording, int(t))
        T_root = np.eye(4) if root is None else root[k]
        for link in model.link_map:
            expected = T_root @ model.get_transform(frame_to=link, frame_from=model.base_link)
            worst = max(worst, float(np.abs(pose_in(edges, link, "odom") - expected).max()))
    return worst


def test_log_a_numpy_trajectory_into_your_own_recording(tmp_path: Path) -> None:
    out = tmp_path / "api.rrd"
    rec = rr.RecordingStream("my_app")
    rec.save(out)
    logger = r2d2_viz.RobotLogger(r2d2_viz.load_urdf(ARM), recording=rec, warn=lambda _: None)
    logger.log_static()
    times = np.linspace(0, 2, 41)
    rng = np.random.default_rng(0)
    q = rng.uniform(-1, 1, (41, len(logger.joints)))
    q[:, logger.joints.index("tool_slide")] = 0.02
    logger.log_joint_positions(times, q)
    logger.log_joint_positions([2.1, 2.2], [[0.5], [0.6]], joints=["elbow"])  # a subset: the others stay
    logger.finish()
    rec.flush()
    rec.disconnect()
    recording = read_recording(out)
    configs = [dict(zip(logger.joints, row, strict=True)) for row in q]
    assert _worst(recording, ARM, np.rint(times * 1e9), configs) < 1e-5
    held = {**configs[-1], "elbow": 0.6}
    assert _worst(recording, ARM, [2_200_000_000], [held]) < 1e-5


def test_a_moving_root_and_a_description_given_as_text(tmp_path: Path) -> None:
    out = tmp_path / "root.rrd"
    rec = rr.RecordingStream("my_app")
    rec.save(out)
    robot = r2d2_viz.parse_urdf(ARM.read_text(), source="arm6 from a string", base_dir=ARM.parent)
    logger = r2d2_viz.RobotLogger(robot, recording=rec, moving_root=True, timestamps=True, warn=lambda _: None)
    logger.log_static()
    n = 5
    stamps = np.datetime64("2026-11-22T12:00:00", "ns") + np.arange(n) * np.timedelta64(100, "ms")
    t = np.column_stack([np.arange(n) * 0.5, np.zeros(n), np.zeros(n)])
    logger.log_joint_positions(
        stamps, np.zeros((n, 6)), root_translation=t, root_quat_xyzw=np.tile([0, 0, 0, 1.0], (n, 1))
    )
    rec.flush()
    rec.disconnect()
    recording = read_recording(out)
    roots = np.tile(np.eye(4), (n, 1, 1))
    roots[:, :3, 3] = t
    zero = [dict.fromkeys(logger.joints, 0.0)] * n
    assert _worst(recording, ARM, stamps.astype(np.int64), zero, root=roots) < 1e-5


def test_bad_arguments_are_one_clear_line(tmp_path: Path) -> None:
    rec = rr.RecordingStream("my_app")
    logger = r2d2_viz.RobotLogger(ARM, recording=rec, warn=lambda _: None)
    with pytest.raises(UsageError, match="2 columns for 1 joints"):
        logger.log_joint_positions([0.0], [[1.0, 2.0]], joints=["elbow"])
    with pytest.raises(UsageError, match="not actuated joints of 'arm6': nose; expected some of its 6: base_yaw"):
        logger.log_joint_positions([0.0], [[1.0]], joints=["nose"])
    with pytest.raises(UsageError, match="finite"):
        logger.log_joint_positions([np.nan], [[1.0]], joints=["elbow"])


def test_the_same_entities_as_the_command_line(tmp_path: Path) -> None:
    out = tmp_path / "api.rrd"
    rec = rr.RecordingStream("my_app")
    rec.save(out)
    logger = r2d2_viz.RobotLogger(ARM, recording=rec, warn=lambda _: None)
    logger.log_static()
    logger.log_joint_positions(np.arange(10) / 30, np.zeros((10, 6)))
    logger.finish()
    rec.flush()
    rec.disconnect()
    result = cli("--urdf", str(ARM), "--motion", "still", "--save", str(tmp_path / "cli.rrd"), "--duration", "0.33")
    assert result.returncode == 0, result.stderr
    assert set(read_recording(out)) == set(read_recording(tmp_path / "cli.rrd"))


def test_the_public_api_is_listed_and_light_to_import() -> None:
    for name in r2d2_viz.__all__:
        assert getattr(r2d2_viz, name) is not None
    code = "import sys, r2d2_viz; print('rerun' in sys.modules, 'yourdfpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_the_example_records_named_frames_for_the_arm(tmp_path: Path) -> None:
    out = tmp_path / "arm.rrd"
    result = subprocess.run(
        [sys.executable, str(REPO / "examples" / "log_trajectory.py"), "--save", str(out), "--seconds", "2"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    children = {c[0] for rows in recording.values() for c in rows.temporal.get("Transform3D:child_frame", [])}
    assert children == {"shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "tool"}
    edges = frame_edges_at(recording, 1_000_000_000)
    tool = pose_in(edges, "tool", "odom")
    assert 0.0 < np.linalg.norm(tool[:3, 3]) < 1.5  # somewhere within the arm's reach of its base


def test_a_xacro_file_with_arguments_through_the_logger(tmp_path: Path) -> None:
    # Universal Robots' ROS 2 description (tests/data/xacro, see its README) with its two arguments; poses checked
    # against yourdfpy on what the unmodified `xacro` command makes of the same file.
    from xacro_cases import plain_xacro

    ur = REPO / "tests" / "data" / "xacro" / "Universal_Robots_ROS2_Description"
    path = ur / "urdf" / "ur.urdf.xacro"
    args = {"ur_type": "ur5e", "name": "ur"}
    reference = plain_xacro(tmp_path, path, args, {"ur_description": ur})
    expanded, err = reference.communicate(timeout=120)
    assert reference.returncode == 0, err
    (tmp_path / "ur.urdf").write_text(expanded)

    out = tmp_path / "ur.rrd"
    rec = rr.RecordingStream("my_app")
    rec.save(out)
    logger = r2d2_viz.RobotLogger(path, mappings=args, recording=rec, warn=lambda _: None)
    assert len(logger.joints) == 6
    logger.log_static()
    q = np.random.default_rng(1).uniform(-2, 2, (5, 6))
    logger.log_joint_positions(np.arange(5) / 10, q)
    logger.finish()
    rec.flush()
    rec.disconnect()
    configs = [dict(zip(logger.joints, row, strict=True)) for row in q]
    times = np.rint(np.arange(5) / 10 * 1e9)
    assert _worst(read_recording(out), tmp_path / "ur.urdf", times, configs) < 1e-5
    with pytest.raises(UsageError, match="arguments for a xacro file"):
        r2d2_viz.RobotLogger(ARM, mappings={"x": "1"}, recording=rec)


def test_a_script_takes_picks_from_the_page() -> None:
    """``serve_tools`` + ``on_pick``: a tool used in the page (its event POSTed as the page does, with the token)
    reaches the script's callback; without the token nothing does."""
    import json
    import socket
    import urllib.error
    import urllib.request

    ports = []
    for _ in range(2):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            ports.append(s.getsockname()[1])
    rec = rr.RecordingStream("test_api_picks")
    picks: list[r2d2_viz.api.Pick] = []
    lines: list[str] = []
    unsubscribe = r2d2_viz.on_pick(picks.append)
    page = r2d2_viz.serve_tools(rec, fixed_frame="map", port=ports[0], web_port=ports[1], say=lines.append)
    try:
        assert page.url.startswith(f"http://localhost:{ports[1]}/")
        event = json.dumps({"tool": "2D Goal Pose", "points": [[0, 0, 0], [0, 2, 0]]}).encode()
        with pytest.raises(urllib.error.HTTPError):
            urllib.request.urlopen(urllib.request.Request(f"http://127.0.0.1:{ports[1]}/event", data=event), timeout=30)
        assert picks == []
        with urllib.request.urlopen(urllib.request.Request(page.url + "event", data=event), timeout=30) as answer:
            assert json.loads(answer.read()) == {"line": "goal: map (0.00, 0.00) yaw 90.0°"}
    finally:
        unsubscribe()
        page.close()
    assert [(p.tool, p.points) for p in picks] == [("2D Goal Pose", ((0.0, 0.0, 0.0), (0.0, 2.0, 0.0)))]
    assert lines == ["goal: map (0.00, 0.00) yaw 90.0°"]
