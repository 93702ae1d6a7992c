"""A bag replay's progress bar (rich, on stderr): the share of the bag's time replayed, megabytes and rate, or a
live replay's position; nothing when not wanted. Values worked out by hand from the bag written here."""

from __future__ import annotations

import io
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from bagmaker import T0, BagSpec, joint_state, string, tf_message, write_bag
from conftest import REPO, cli
from terminal import on_a_terminal

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.progress import progress_bar
from r2d2_viz.robot.model import default_urdf_path, load_urdf
from r2d2_viz.sources.bags.bag import Bag, open_bag
from r2d2_viz.sources.base import ArraySource
from r2d2_viz.sources.plan import RunPlan, plan_bag, plan_motion
from r2d2_viz.sources.playback import Window

S = 1_000_000_000


@dataclass(frozen=True)
class _Config:
    progress: bool = True
    live: bool = False


def _bag(tmp_path: Path) -> Bag:
    """/tf every 100 ms for 10 s: the bag lasts 9.9 s."""
    spec = BagSpec()
    for k in range(100):
        t = T0 + k * S // 10
        spec.add("/tf", t, tf_message([(t, "odom", "base", (k, 0, 0), (0, 0, 0, 1))]))
    return open_bag(write_bag(tmp_path / "walk", spec))


def _shown(plan: RunPlan, config: _Config, windows: list[Window], monkeypatch: pytest.MonkeyPatch) -> str:
    err = io.StringIO()
    monkeypatch.setattr(sys, "stderr", err)
    with progress_bar(plan, config) as advance:
        assert advance is not None
        for window in windows:
            advance(window)
    return err.getvalue()


def test_a_saved_replay_shows_the_share_of_the_bag_and_its_megabytes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with _bag(tmp_path) as bag:
        plan = plan_bag(bag)
        half = [Window(T0 + 2 * S, nbytes=1_000_000), Window(T0 + 99 * S // 20, nbytes=2_000_000)]  # 4.95 of 9.9 s
        shown = _shown(plan, _Config(), half, monkeypatch)
        assert shown.startswith("walk ") and " 50% " in shown and "3 MB," in shown and "\r" not in shown
        whole = list(plan.windows(1000))
        shown = _shown(plan, _Config(), whole, monkeypatch)
    assert " 100% " in shown and len(shown.splitlines()) == 1


def test_a_live_replay_shows_its_position(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with _bag(tmp_path) as bag:
        shown = _shown(plan_bag(bag), _Config(live=True), [Window(T0 + 3 * S)], monkeypatch)
    assert shown.startswith("walk ") and shown.rstrip().endswith("3.0 / 9.9 s")


def test_a_live_replay_shows_where_it_has_got_between_windows(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    err = io.StringIO()
    monkeypatch.setattr(sys, "stderr", err)
    with _bag(tmp_path) as bag, progress_bar(plan_bag(bag), _Config(live=True)) as bar:
        assert bar is not None
        bar.at(T0 + 45 * S // 10)  # 4.5 s into the bag, the window not done
    assert err.getvalue().rstrip().endswith("4.5 / 9.9 s")


def test_no_bar_when_not_wanted_or_not_a_bag(tmp_path: Path) -> None:
    with _bag(tmp_path) as bag, progress_bar(plan_bag(bag), _Config(progress=False)) as advance:
        assert advance is None
    robot = load_urdf(default_urdf_path())
    motion = ArraySource(np.zeros(1, dtype=np.int64), ["j"], np.zeros((1, 1)))
    with progress_bar(plan_motion(compile_tree(robot), motion, "odom"), _Config()) as advance:
        assert advance is None


# --- the real CLI: on a real pseudo-terminal, and off one -----------------------------------------------------

ARM = REPO / "examples" / "arm6.urdf"
JOINTS = ("base_yaw", "shoulder_pitch", "elbow", "wrist_pitch", "wrist_roll")


def _arm_bag(path: Path) -> Path:
    spec = BagSpec().add("/robot_description", T0, string(ARM.read_text()))
    for k in range(2000):  # 20 s at 100 Hz
        t = T0 + k * 10_000_000
        spec.add("/joint_states", t, joint_state(t, JOINTS, [0.0005 * k] * len(JOINTS)))
    return write_bag(path, spec)


def test_a_conversion_shows_a_bar_on_a_terminal(tmp_path: Path) -> None:
    bag = _arm_bag(tmp_path / "arm")
    code, shown = on_a_terminal("--bag", str(bag), "--save", str(tmp_path / "out.rrd"))
    assert code == 0, shown
    assert "100%" in shown  # the bar's percent of the bag, at the end
    assert "MB/s" in shown
    assert "arm" in shown  # the bag's name labels the bar
    assert "r2d2-viz: 2000 joint states" in shown


def test_off_a_terminal_only_the_summary_line(tmp_path: Path) -> None:
    bag = _arm_bag(tmp_path / "arm")
    result = cli("--bag", str(bag), "--save", str(tmp_path / "out.rrd"))
    assert result.returncode == 0, result.stderr
    assert "\r" not in result.stderr and "\x1b[" not in result.stderr
    assert [line for line in result.stderr.splitlines() if line.strip()] == [
        f"r2d2-viz: 2000 joint states from {bag} to {tmp_path / 'out.rrd'}"
    ]


def test_a_live_replay_shows_its_position_in_the_bag(tmp_path: Path) -> None:
    bag = _arm_bag(tmp_path / "arm")
    code, shown = on_a_terminal("--bag", str(bag), "--save", str(tmp_path / "out.rrd"), "--realtime", "--speed", "10")
    assert code == 0, shown
    assert "/ 20.0 s" in shown  # "12.3 / 20.0 s": its position in the 19.99 s bag


def test_ctrl_c_leaves_a_live_replays_bar_where_it_stopped(tmp_path: Path) -> None:
    # issue 44: the bar sat at 0.0 (a small bag is one window) and, after Ctrl-C, showed the whole bag replayed
    import os
    import pty
    import re
    import signal
    import subprocess
    import time

    bag = _arm_bag(tmp_path / "arm")
    leader, follower = pty.openpty()
    exe = str(Path(sys.executable).parent / "r2d2-viz")
    env = {**os.environ, "COLUMNS": "160", "TERM": "xterm"}
    out = tmp_path / "out.rrd"
    command = [exe, "--bag", str(bag), "--save", str(out), "--realtime"]  # 20 s at 1x
    proc = subprocess.Popen(command, stdin=follower, stdout=follower, stderr=follower, env=env)
    os.close(follower)
    shown, interrupted_at = b"", None
    while True:
        try:
            data = os.read(leader, 65536)
        except OSError:
            break
        if not data:
            break
        shown += data
        if interrupted_at is None and b"/ 20.0 s" in shown:
            interrupted_at = time.monotonic() + 3  # Ctrl-C some 3 s into the bag (a wait, not a measurement)
        if interrupted_at is not None and interrupted_at <= time.monotonic() and proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            interrupted_at = float("inf")
    os.close(leader)
    assert proc.wait(timeout=60) == 0
    positions = [float(p) for p in re.findall(r"(\d+\.\d) / 20\.0 s", shown.decode(errors="replace"))]
    assert len(set(positions)) > 2, positions  # it moved while the bag played
    assert 0 < positions[-1] < 20.0, positions  # and stayed where the replay stopped
