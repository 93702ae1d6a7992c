"""``--ray`` (issue 25): the same conversions as Ray tasks on a local Ray (two CPUs, no dashboard) inside a
network namespace of its own (``unshare -n``: loopback only) — outputs identical to ``--jobs``'s, a worker that
dies fails its bag while the rest finish — and, without Ray, one line saying how to install it."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import cli
from fleetbags import still_bag, turn_bag, walk_bag
from rerun.chunk import RrdReader
from rrd import read_recording

HAS_RAY = importlib.util.find_spec("ray") is not None
CAN_UNSHARE = shutil.which("unshare") is not None and shutil.which("ip") is not None and os.geteuid() == 0


def _in_own_network(*args: str, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    exe = str(Path(sys.executable).parent / "r2d2-viz")
    script = 'ip link set lo up && exec "$@"'
    return subprocess.run(
        ["unshare", "-n", "sh", "-c", script, "sh", exe, *args],
        capture_output=True,
        text=True,
        timeout=400,
        env={**os.environ, **env},
    )


def _content(rrd: Path) -> dict[str, object]:
    """Every entity's rows but the properties (their start time is the wall clock's)."""
    return {e: (r.static, r.times, r.temporal) for e, r in read_recording(rrd).items() if e != "/__properties"}


@pytest.mark.skipif(not HAS_RAY, reason="ray is not installed: pip install 'r2d2-viz[ray]'")
@pytest.mark.skipif(not CAN_UNSHARE, reason="needs root, unshare and ip for a loopback-only network")
def test_ray_tasks_write_what_the_processes_write_and_a_dead_worker_fails_its_bag(tmp_path: Path) -> None:
    bags = [walk_bag(tmp_path / "walk"), turn_bag(tmp_path / "turn", storage="sqlite3"), still_bag(tmp_path / "dies")]
    ray_out, jobs_out = tmp_path / "ray", tmp_path / "jobs"
    args = ["--bag", *map(str, bags)]
    result = _in_own_network(
        *args, "--save-dir", str(ray_out), "--ray", "--jobs", "2", env={"R2D2_VIZ_FLEET_KILL": "dies"}
    )
    assert result.returncode == 2, result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and errors[0].startswith(f"error: {bags[2]}: its Ray worker failed"), result.stderr
    assert "2 converted, 1 failed" in result.stderr
    assert sorted(p.name for p in ray_out.iterdir()) == ["turn.rbl", "turn.rrd", "walk.rbl", "walk.rrd"]  # none of dies

    result = cli(*args[:3], "--save-dir", str(jobs_out), "--jobs", "2")
    assert result.returncode == 0, result.stderr
    for name in ("walk.rrd", "turn.rrd"):
        ids = {str(RrdReader(d / name).recordings()[0].recording_id) for d in (ray_out, jobs_out)}
        assert len(ids) == 1
        assert _content(ray_out / name) == _content(jobs_out / name)


def test_without_ray_one_line_says_how_to_install_it(tmp_path: Path) -> None:
    fake = tmp_path / "site" / "ray"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('No module named ray (hidden by the test)')\n")
    bag = still_bag(tmp_path / "bag")
    result = cli(
        "--bag", str(bag), "--save-dir", str(tmp_path / "out"), "--ray", env={"PYTHONPATH": str(tmp_path / "site")}
    )
    assert result.returncode == 2
    assert result.stderr.strip() == "error: --ray needs Ray, which is not installed: pip install 'r2d2-viz[ray]'"
    assert not (tmp_path / "out").exists()
