"""LeRobot's own loader for the export's tests: ``lerobot[dataset]==0.6.1`` on Python 3.12 in a cached venv of its
own (it needs torch, which the project's venv must not get), as ``tests/sources/live/ros_node.py`` keeps rclpy's.

``${XDG_CACHE_HOME:-~/.cache}/r2d2-viz-test/lerobot-0.6.1-<hash of its requirements>``, made once under a file lock
and validated by a marker holding the requirements plus an import check. Building it downloads PyPI's torch with its
CUDA libraries (about 5 GB installed, several minutes on a fresh machine: see docs/export.md); without Python 3.12
or PyPI the tests skip — or fail under CI (``CI`` set). The loader then runs offline (``HF_HUB_OFFLINE=1``).

``python3 tests/run/lerobot_venv.py`` builds it alone: ``.ci/run`` starts that in the background before the tests, so
the test waits on the file lock for a build already under way instead of starting one (the build is about 10 min).
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import subprocess
from pathlib import Path

REQUIREMENTS = ("lerobot[dataset]==0.6.1",)
PYTHONS = ("/root/.pyenv/versions/3.12.1/bin/python", "python3.12")
CHECK = "import torch, lerobot.datasets.lerobot_dataset"
LOADER = Path(__file__).resolve().parent / "lerobot_load.py"


def unavailable(reason: str) -> None:
    """Skip with ``reason`` — or fail, when running under CI (``CI`` set and non-empty)."""
    import pytest  # here, not at the top: CI runs this file as a script, before the project's venv exists

    if os.environ.get("CI"):
        pytest.fail(f"LeRobot loader prerequisite missing under CI: {reason}", pytrace=False)
    pytest.skip(reason)


def cache_root() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "r2d2-viz-test"


def python312() -> str | None:
    for candidate in PYTHONS:
        found = shutil.which(candidate) or (candidate if Path(candidate).exists() else None)
        if found:
            return found
    return None


def _valid(python: Path, marker: Path, spec: str) -> bool:
    if not python.exists() or not marker.exists() or marker.read_text() != spec:
        return False
    return subprocess.run([str(python), "-c", CHECK], capture_output=True, timeout=300).returncode == 0


def ensure_venv() -> Path:
    """The Python of the cached LeRobot venv, made (from PyPI) if missing or stale, under a file lock."""
    base = python312()
    if base is None:
        raise RuntimeError("no Python 3.12 (LeRobot 0.6.1 needs it)")
    spec = "\n".join(REQUIREMENTS) + "\n"
    root = cache_root() / f"lerobot-0.6.1-{hashlib.sha256(spec.encode()).hexdigest()[:8]}"
    python, marker = root / "bin" / "python", root / "r2d2-viz-requirements.txt"
    cache_root().mkdir(parents=True, exist_ok=True)
    with open(root.with_name(root.name + ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if _valid(python, marker, spec):
            return python
        shutil.rmtree(root, ignore_errors=True)
        for step in (
            [base, "-m", "venv", str(root)],
            [str(python), "-m", "pip", "install", "-q", *REQUIREMENTS],
        ):
            done = subprocess.run(step, capture_output=True, text=True, timeout=3600)
            if done.returncode != 0:
                shutil.rmtree(root, ignore_errors=True)
                raise RuntimeError(f"{' '.join(step[:4])} failed: {done.stderr.strip()[-800:]}")
        marker.write_text(spec)
        if not _valid(python, marker, spec):
            raise RuntimeError(f"the venv at {root} does not import lerobot")
        return python


def require_lerobot() -> Path:
    """For a test: the LeRobot venv's Python (skip / CI-fail when it cannot be made)."""
    try:
        return ensure_venv()
    except (RuntimeError, subprocess.TimeoutExpired) as exc:
        unavailable(f"cannot make the LeRobot 0.6.1 venv: {exc}")
        raise


def load(python: Path, root: Path, out: Path) -> subprocess.CompletedProcess[str]:
    """LeRobot's ``LeRobotDataset(repo_id, root=root)`` in the venv, every frame dumped to ``out`` (.npz)."""
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "HF_DATASETS_OFFLINE": "1", "HF_HOME": str(out.parent / "hf")}
    return subprocess.run(
        [str(python), str(LOADER), str(root), str(out)], capture_output=True, text=True, timeout=900, env=env
    )


if __name__ == "__main__":
    print(ensure_venv())
