"""A bag replay's progress: a rich bar on stderr when it is a terminal (run here under a real pseudo-terminal), and
nothing but the summary line off one."""

from __future__ import annotations

import os
import pty
import select
import sys
import time
from pathlib import Path

from bagmaker import T0, BagSpec, joint_state, string, write_bag
from conftest import REPO, cli

ARM = REPO / "examples" / "arm6.urdf"
JOINTS = ("base_yaw", "shoulder_pitch", "elbow", "wrist_pitch", "wrist_roll")


def _bag(path: Path) -> Path:
    spec = BagSpec().add("/robot_description", T0, string(ARM.read_text()))
    for k in range(2000):  # 20 s at 100 Hz
        t = T0 + k * 10_000_000
        spec.add("/joint_states", t, joint_state(t, JOINTS, [0.0005 * k] * len(JOINTS)))
    return write_bag(path, spec)


def _on_a_terminal(args: list[str], timeout: float = 120) -> tuple[int, str]:
    """The CLI with stdout and stderr on a pseudo-terminal: (exit code, what the terminal showed)."""
    app = str(Path(sys.executable).parent / "r2d2-viz")
    pid, fd = pty.fork()
    if pid == 0:  # the child: the terminal is its stdin, stdout and stderr
        os.environ["COLUMNS"] = "120"
        os.execv(app, [app, *args])
    out = b""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], 0.5)
        if ready:
            try:
                data = os.read(fd, 65536)
            except OSError:  # the child closed the terminal
                break
            if not data:
                break
            out += data
    _, status = os.waitpid(pid, 0)
    os.close(fd)
    return os.waitstatus_to_exitcode(status), out.decode("utf-8", "replace")


def test_a_conversion_shows_a_bar_on_a_terminal(tmp_path: Path) -> None:
    bag = _bag(tmp_path / "arm")
    code, shown = _on_a_terminal(["--bag", str(bag), "--save", str(tmp_path / "out.rrd")])
    assert code == 0, shown
    assert "100%" in shown  # the bar's percent of the bag, at the end
    assert "MB/s" in shown
    assert "arm" in shown  # the bag's name labels the bar
    assert "r2d2-viz: 2000 samples" in shown


def test_off_a_terminal_only_the_summary_line(tmp_path: Path) -> None:
    bag = _bag(tmp_path / "arm")
    result = cli("--bag", str(bag), "--save", str(tmp_path / "out.rrd"))
    assert result.returncode == 0, result.stderr
    assert "\r" not in result.stderr and "\x1b[" not in result.stderr
    assert [line for line in result.stderr.splitlines() if line.strip()] == [
        f"r2d2-viz: 2000 samples from {bag} to {tmp_path / 'out.rrd'}"
    ]


def test_a_live_replay_shows_its_position_in_the_bag(tmp_path: Path) -> None:
    bag = _bag(tmp_path / "arm")
    code, shown = _on_a_terminal(
        ["--bag", str(bag), "--save", str(tmp_path / "out.rrd"), "--realtime", "--speed", "10"]
    )
    assert code == 0, shown
    assert "/ 20.0 s" in shown  # "12.3 / 20.0 s": its position in the 19.99 s bag
