"""Live runs and signals: paced to the wall clock, streamed to a real Rerun gRPC server, finalised on
SIGINT/SIGTERM; batch runs interrupted leave nothing behind."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from conftest import listening_addresses, rerun_viewer
from rrd import read_recording, tf_by_child

pytestmark = pytest.mark.slow


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _command() -> list[str]:
    exe = Path(sys.executable).parent / "r2d2-viz"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "r2d2_viz"]


@contextmanager
def _process(args: list[str], **kwargs) -> Iterator[subprocess.Popen[str]]:
    proc = subprocess.Popen(
        args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True, **kwargs
    )
    try:
        yield proc
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)


def _wait_for_port(port: int, timeout: float = 30) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise TimeoutError(f"nothing listens on {port}")


def _verified(path: Path) -> None:
    """``rerun rrd verify`` (Rerun's own check, footers included) accepts the file."""
    viewer = rerun_viewer()
    assert viewer, "the rerun binary ships with rerun-sdk"
    check = subprocess.run([viewer, "rrd", "verify", str(path)], capture_output=True, text=True, timeout=120)
    assert check.returncode == 0, check.stdout + check.stderr


@pytest.mark.parametrize("how", ["batch", "realtime", "connect", "spawn"])
def test_every_recording_the_app_writes_has_its_footer(tmp_path: Path, how: str) -> None:
    """Rerun pages an .rrd from disk only with its footer (the chunk manifest): batch and live saves alike."""
    out = tmp_path / "out.rrd"
    args, env = [*_command(), "--save", str(out), "--duration", "1"], dict(os.environ)
    if how == "realtime":
        args.append("--realtime")
    port = _free_port()
    viewer = rerun_viewer()
    assert viewer, "the rerun binary ships with rerun-sdk"
    with _process([viewer, "--port", str(port), "--save", str(tmp_path / "received.rrd")]) as server:
        _wait_for_port(port)
        if how == "connect":
            args += ["--connect", f"rerun+http://127.0.0.1:{port}/proxy"]
        elif how == "spawn":  # a viewer already listens on the port: --spawn streams to it, starts nothing
            args += ["--spawn", "--port", str(port)]
            env["DISPLAY"] = env.get("DISPLAY") or ":99"
        result = subprocess.run(args, capture_output=True, text=True, timeout=120, env=env)
        os.killpg(server.pid, signal.SIGINT)
    assert result.returncode == 0, result.stderr
    assert len(tf_by_child(read_recording(out))["axis"].times) == 30
    _verified(out)


def test_connect_streams_paced_frames_to_a_running_rerun_server(tmp_path: Path) -> None:
    viewer = rerun_viewer()
    assert viewer, "the rerun binary ships with rerun-sdk"
    port, received = _free_port(), tmp_path / "received.rrd"
    with _process([viewer, "--port", str(port), "--save", str(received)]) as server:
        _wait_for_port(port)
        start = time.monotonic()
        result = subprocess.run(
            [*_command(), "--connect", f"rerun+http://127.0.0.1:{port}/proxy", "--duration", "2"],
            capture_output=True,
            text=True,
            timeout=120,
        )
        elapsed = time.monotonic() - start
        assert result.returncode == 0, result.stderr
        time.sleep(1.0)
        os.killpg(server.pid, signal.SIGINT)
        server.wait(timeout=30)
    assert elapsed >= 2.0 * 59 / 60  # frame 59 is sent at t = 59/30 s, not before
    recording = read_recording(received)
    assert len(tf_by_child(recording)["axis"].times) == 60


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_finalises_a_live_save(tmp_path: Path, signum: int) -> None:
    out = tmp_path / "live.rrd"
    with _process([*_command(), "--save", str(out), "--realtime"]) as proc:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not list(tmp_path.glob(".live.rrd.*.partial")):
            time.sleep(0.05)
        time.sleep(2.0)  # ~60 frames
        os.killpg(proc.pid, signum)
        _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 0, stderr
    assert "stopped by signal" in stderr
    # frames go out one by one here: each joint's excursion is still reported once (tilt +1°, periscope > 0)
    assert stderr.count("'tilt' left its URDF limits") == 1 and stderr.count("'periscope' left its URDF limits") == 1
    frames = len(tf_by_child(read_recording(out))["axis"].times)
    reported = int(stderr.split("r2d2-viz: ")[1].split(" samples")[0])
    assert frames == reported and frames >= 30
    assert not list(tmp_path.glob("*.partial"))
    _verified(out)  # finalised on the signal: footer and all


def test_an_interrupted_batch_save_removes_its_partial_file_and_keeps_the_old_one(tmp_path: Path) -> None:
    out = tmp_path / "keep.rrd"
    out.write_bytes(b"an older recording")
    with _process([*_command(), "--save", str(out), "--duration", "86400"]) as proc:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not list(tmp_path.glob(".keep.rrd.*.partial")):
            time.sleep(0.05)
        time.sleep(0.5)
        os.killpg(proc.pid, signal.SIGTERM)
        _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr
    assert out.read_bytes() == b"an older recording"
    assert not list(tmp_path.glob("*.partial"))


def test_serve_listens_on_loopback_only_and_a_signal_finalises_its_save(tmp_path: Path) -> None:
    port, web_port, out = _free_port(), _free_port(), tmp_path / "served.rrd"
    args = [*_command(), "--serve", "--port", str(port), "--web-port", str(web_port), "--save", str(out)]
    with _process(args) as proc:
        _wait_for_port(web_port)
        assert listening_addresses(web_port) == {"127.0.0.1"}
        assert not listening_addresses(port)  # no Rerun gRPC server: the recording goes through the tokened page
        time.sleep(1.5)
        os.killpg(proc.pid, signal.SIGINT)
        _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 0, stderr
    assert re.search(rf"rerun http://localhost:{web_port}/[\w-]+/recording\.rrd", stderr)  # where to look
    assert len(tf_by_child(read_recording(out))["axis"].times) >= 15
    _verified(out)
    assert not listening_addresses(port) and not listening_addresses(web_port)  # the server went with the app
