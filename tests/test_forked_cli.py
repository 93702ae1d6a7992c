"""The suite's ``cli()`` forks its runs from a warm interpreter (``tests/forked_cli.py``): what a test reads of a
forked run — exit code, stdout, stderr, the files written — is what the console script in a fresh interpreter
gives (the golden side here: ``cli(fresh=True)`` runs ``.venv/bin/r2d2-viz`` through ``subprocess.run``)."""

from __future__ import annotations

import os
from pathlib import Path

import forked_cli
import pytest
from conftest import cli

from r2d2_viz.viewer.files.whole import rrd_complete


@pytest.fixture(autouse=True)
def _forking(monkeypatch: pytest.MonkeyPatch) -> None:
    """These tests are about the forked runs: a whole-suite ``R2D2_TEST_FRESH_CLI=1`` (every run fresh) not here."""
    monkeypatch.delenv("R2D2_TEST_FRESH_CLI", raising=False)


def _same(a: str, b: str, tmp: Path, fresh_tmp: Path) -> None:
    assert a.replace(str(tmp), "<tmp>") == b.replace(str(fresh_tmp), "<tmp>")


@pytest.mark.parametrize(
    "args",
    [
        ("--help",),  # stdout, exit 0, no rerun
        ("--rate", "0"),  # the exit-2 line
        ("--headless", "--duration", "0.2"),  # Rerun's own log lines off (RUST_LOG=off around its import)
        ("--save", "{tmp}/run.rrd", "--duration", "0.3"),  # a real save, its file whole
    ],
    ids=["help", "exit-2", "headless", "save"],
)
def test_a_forked_run_says_and_writes_what_a_fresh_console_script_does(args: tuple[str, ...], tmp_path: Path) -> None:
    runs = {}
    for fresh in (True, False):
        folder = tmp_path / ("fresh" if fresh else "forked")
        folder.mkdir()
        runs[fresh] = (folder, cli(*(a.format(tmp=folder) for a in args), cwd=folder, fresh=fresh))
    (fresh_dir, fresh), (forked_dir, forked) = runs[True], runs[False]
    assert forked.returncode == fresh.returncode
    _same(forked.stdout, fresh.stdout, forked_dir, fresh_dir)
    _same(forked.stderr, fresh.stderr, forked_dir, fresh_dir)
    assert sorted(p.name for p in forked_dir.iterdir()) == sorted(p.name for p in fresh_dir.iterdir())
    for saved in forked_dir.glob("*.rrd"):
        assert rrd_complete(saved)


def test_a_forked_run_is_forked_and_its_cpu_counted(tmp_path: Path) -> None:
    before = forked_cli.child_cpu
    result = cli("--rate", "0", cwd=tmp_path)
    assert result.returncode == 2
    assert forked_cli.child_cpu > before  # the run went through the zygote, and cpu_per_test sees its CPU


def test_an_environment_that_changes_how_python_or_rerun_start_runs_fresh() -> None:
    base = dict(os.environ)
    assert forked_cli.forks(base)
    for key, value in (("PYTHONPATH", "/nowhere"), ("RUST_LOG", "info"), ("R2D2_VIZ_DEBUG", "1"), ("LANG", "C")):
        assert not forked_cli.forks({**base, key: value}), key
    assert forked_cli.forks({**base, "DISPLAY": ""})


def test_a_run_that_is_a_grpc_client_runs_fresh() -> None:
    base = dict(os.environ)
    assert forked_cli.forks(base, ("--serve", "--duration", "1"))  # a server answers from a forked child
    for args in (("--render", "x.rrd"), ("--connect",), ("--connect=rerun+http://127.0.0.1:1/proxy",), ("--spawn",)):
        assert not forked_cli.forks(base, args), args
    assert not forked_cli.forks(base, ("--dataset", "fleet"))


def test_a_run_over_its_timeout_is_killed_as_subprocess_run_does(tmp_path: Path) -> None:
    import subprocess

    with pytest.raises(subprocess.TimeoutExpired):
        cli("--headless", "--realtime", "--duration", "60", cwd=tmp_path, timeout=3)


def test_a_ctrl_c_to_the_workers_process_group_leaves_the_zygote_serving(tmp_path: Path) -> None:
    import signal

    cli("--rate", "0", cwd=tmp_path)
    zygote = forked_cli._the_zygote()
    os.kill(zygote.proc.pid, signal.SIGINT)  # what a killpg(SIGINT) of the worker's group does to it
    assert cli("--rate", "0", cwd=tmp_path).returncode == 2
    assert forked_cli._the_zygote() is zygote and zygote.proc.poll() is None
