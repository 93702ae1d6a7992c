"""Real ROS 2 nodes for the live tests: PyPI's ``ros-rclpy[fastrtps]`` wheels in a cached venv of their own.

The wheels' ``.pth`` re-executes Python with ``LD_LIBRARY_PATH`` set, so they never go into the project's venv:
each distro gets ``${XDG_CACHE_HOME:-~/.cache}/r2d2-viz-test/rclpy-<distro>-<hash of its requirements>``, created
once (about 20 s) and validated by a marker holding the pinned requirements plus an import check (new requirements:
a new folder, so a run of older code never finds its venv rebuilt under it). Everything that talks DDS runs in
a network namespace with only loopback (``unshare -n``, root), so nothing leaves the machine; without root or
``unshare`` the tests skip — or fail under CI (``CI`` set).
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
NODES = HERE / "nodes"
DISTROS: dict[str, tuple[str, ...]] = {
    # rclpy 7.1.6 is Jazzy (Fast DDS 2.14), 9.1.2 is Kilted (Fast DDS 3); the message wheels of the same distro.
    "jazzy": ("ros-rclpy[fastrtps]==7.1.6", "ros-std-msgs==5.3.6", "ros-sensor-msgs==5.3.6", "ros-nav-msgs==5.3.6"),
    "kilted": ("ros-rclpy[fastrtps]==9.1.2", "ros-std-msgs==5.5.1", "ros-sensor-msgs==5.5.1", "ros-nav-msgs==5.5.1"),
}
CHECK = "import rclpy, std_msgs.msg, sensor_msgs.msg, nav_msgs.msg, rmw_fastrtps_cpp"


def unavailable(reason: str) -> None:
    """Skip with ``reason`` — or fail, when running under CI (``CI`` set and non-empty)."""
    if os.environ.get("CI"):
        pytest.fail(f"live prerequisite missing under CI: {reason}", pytrace=False)
    pytest.skip(reason)


def cache_root() -> Path:
    """``${XDG_CACHE_HOME:-~/.cache}/r2d2-viz-test``."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "r2d2-viz-test"


def netns_missing() -> str | None:
    """Why a loopback-only network namespace cannot be made here, or None."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        return "needs root for 'unshare -n' (a network namespace with only loopback)"
    for tool in ("unshare", "ip"):
        if shutil.which(tool) is None:
            return f"'{tool}' not found (util-linux / iproute2)"
    probe = subprocess.run(["unshare", "-n", "true"], capture_output=True, text=True, timeout=30)
    if probe.returncode != 0:
        return f"'unshare -n' failed: {probe.stderr.strip()[:200]}"
    return None


def _valid(python: Path, marker: Path, spec: str) -> bool:
    if not python.exists() or not marker.exists() or marker.read_text() != spec:
        return False
    check = subprocess.run([str(python), "-c", CHECK], capture_output=True, timeout=120)
    return check.returncode == 0


_checked: dict[str, Path] = {}  # distro -> its Python, once checked by this process (the venv is never changed)


def ensure_venv(distro: str) -> Path:
    """The Python of the cached ``ros-rclpy`` venv of ``distro``, created (from PyPI) if missing or stale.

    Made and checked under a file lock, so that pytest-xdist workers (or two test runs) never build it twice;
    a process checks it once."""
    if distro in _checked:
        return _checked[distro]
    _checked[distro] = _ensure_venv(distro)
    return _checked[distro]


def _ensure_venv(distro: str) -> Path:
    requirements = DISTROS[distro]
    spec = "\n".join(requirements) + "\n"
    root = cache_root() / f"rclpy-{distro}-{hashlib.sha256(spec.encode()).hexdigest()[:8]}"
    python, marker = root / "bin" / "python", root / "r2d2-viz-requirements.txt"
    cache_root().mkdir(parents=True, exist_ok=True)
    with open(root.with_name(root.name + ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if _valid(python, marker, spec):
            return python
        shutil.rmtree(root, ignore_errors=True)
        steps = [
            [sys.executable, "-m", "venv", str(root)],
            [str(python), "-m", "pip", "install", "-q", *requirements],
        ]
        for step in steps:
            done = subprocess.run(step, capture_output=True, text=True, timeout=900)
            if done.returncode != 0:
                shutil.rmtree(root, ignore_errors=True)
                raise RuntimeError(f"{' '.join(step[:4])} failed: {done.stderr.strip()[-800:]}")
        marker.write_text(spec)
        if not _valid(python, marker, spec):
            raise RuntimeError(f"the {distro} venv at {root} does not import rclpy and its messages")
        return python


def require_live(distro: str) -> Path:
    """For a test: the distro's Python, after checking the namespace can be made (skip / CI-fail otherwise)."""
    missing = netns_missing()
    if missing:
        unavailable(missing)
    try:
        return ensure_venv(distro)
    except (RuntimeError, subprocess.TimeoutExpired) as exc:
        unavailable(f"cannot install the {distro} rclpy wheels from PyPI: {exc}")
        raise


def in_netns(command: list[str], timeout: float, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """Run ``command`` in a fresh network namespace where only ``lo`` exists (and is up)."""
    wrapped = ["unshare", "-n", "sh", "-c", 'ip link set lo up && exec "$@"', "sh", *command]
    return subprocess.run(wrapped, capture_output=True, text=True, timeout=timeout, env={**os.environ, **(env or {})})
