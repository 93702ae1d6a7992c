"""Shared fixtures: the installed CLI, the tutorial model, one recording made once per run.

The suite runs on pytest-xdist workers (``-n auto --dist worksteal`` in pyproject), each test on whichever
worker is free: session fixtures are made once per worker, and anything expensive that tests of several
workers read is made once per run with :func:`made_once`. Nothing may assume it runs alone: ports are free
ports, files go to ``tmp_path``, processes are found by their own pid or port.
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import socket
import subprocess
import sys
import sysconfig
from collections.abc import Callable
from pathlib import Path
from typing import Any

import forked_cli
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_REFERENCE = REPO.parent / "shared" / "reference"


def example_robots() -> Path:
    """The ``robots`` folder of the installed example-robot-data (a test dependency)."""
    for root in {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}:
        robots = Path(root) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if robots.is_dir():
            return robots
    raise AssertionError("example-robot-data is a test dependency: pip install '.[test]'")


def cli(
    *args: str, timeout: float = 120, env: dict[str, str] | None = None, cwd: Path | None = None, fresh: bool = False
) -> subprocess.CompletedProcess[str]:
    """Run the installed ``r2d2-viz`` command in a process of its own: forked from a warm interpreter that has
    imported what every run imports (``forked_cli``), or with ``fresh=True`` the console script in a fresh one."""
    exe = Path(sys.executable).parent / "r2d2-viz"
    command = [str(exe)] if exe.exists() else [sys.executable, "-m", "r2d2_viz"]
    environment = {**os.environ, **(env or {})}
    if not fresh and exe.exists() and forked_cli.forks(environment, args):
        return forked_cli.run(command, args, environment, cwd, timeout)
    return subprocess.run([*command, *args], capture_output=True, text=True, timeout=timeout, env=environment, cwd=cwd)


@pytest.fixture(scope="session")
def tutorial_urdf() -> Path:
    from r2d2_viz.robot.model import default_urdf_path

    return default_urdf_path()


def made_once(tmp_path_factory: pytest.TempPathFactory, name: str, make: Callable[[Path], None]) -> Path:
    """The folder ``name``, filled by ``make(folder)`` once per test run and shared by every xdist worker.

    The first caller makes it under a file lock while the others wait; a ``make`` that raised left no mark,
    so the next caller tries again (and fails the same way). Tests only read what is inside.
    """
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # …/pytest-N/popen-gwK: the parent is the run's, shared by its workers
    folder = root / "made-once" / name
    folder.parent.mkdir(parents=True, exist_ok=True)
    with open(folder.parent / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder.parent / f"{name}.done").exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            (folder.parent / f"{name}.done").touch()
    return folder


@pytest.fixture(scope="session")
def lap_recording(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, subprocess.CompletedProcess[str]]:
    """``r2d2-viz --save out.rrd`` with every default: one 48 s lap of the tutorial."""

    def make(folder: Path) -> None:
        result = cli("--save", str(folder / "out.rrd"))
        assert result.returncode == 0, result.stderr
        (folder / "result.json").write_text(json.dumps([result.args, result.returncode, result.stdout, result.stderr]))

    folder = made_once(tmp_path_factory, "lap", make)
    args, returncode, stdout, stderr = json.loads((folder / "result.json").read_text())
    return folder / "out.rrd", subprocess.CompletedProcess(args, returncode, stdout, stderr)


def rerun_viewer() -> str | None:
    from r2d2_viz.viewer.sinks import viewer_executable

    return viewer_executable()


def pytest_configure(config: pytest.Config) -> None:
    """The tests exercise the *installed* package (``pip install .``), never the source tree."""
    import r2d2_viz

    if Path(r2d2_viz.__file__).resolve().is_relative_to(REPO / "r2d2_viz"):
        raise pytest.UsageError(
            "r2d2_viz was imported from the source tree; install it (pip install '.[test]') and run "
            "`pytest` (not `python -m pytest`, which puts the checkout first on sys.path)"
        )


def listening_addresses(port: int) -> set[str]:
    """Addresses a local TCP port listens on, read from /proc/net/tcp{,6}."""
    out = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, hex_port = local.split(":")
            if state == "0A" and int(hex_port, 16) == port:  # 0A: LISTEN
                out.add(socket.inet_ntoa(bytes.fromhex(address)[::-1]) if len(address) == 8 else address)
    return out


def kill_all(proc: subprocess.Popen[str], children: list[Any]) -> None:
    """A test's app and the processes it started (``psutil.Process``), whatever state they were left in."""
    import contextlib

    import psutil

    for child in children:
        with contextlib.suppress(psutil.NoSuchProcess):
            child.kill()
    proc.kill()
    proc.wait()


@pytest.fixture
def without_cyclonedds(monkeypatch: pytest.MonkeyPatch) -> None:
    """This Python as on a machine where PyPI has no cyclonedds wheel: importing it fails."""
    import builtins

    real_import = builtins.__import__

    def no_cyclone(name: str, *args: object, **kwargs: object) -> object:
        if name.startswith("cyclonedds"):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)  # type: ignore[arg-type]

    for name in [m for m in sys.modules if m.startswith("cyclonedds")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setattr(builtins, "__import__", no_cyclone)
