"""Issue 36, finding 6: a fleet accounts for every path given. Found with the installed CLI: a bag and a link to it
said "2 converted" of 3 given; a bag that never finishes reading (a hung mount) said "1 not done" at Ctrl-C without
naming it; ``cd run && r2d2-viz --bag . --save-dir ../out`` wrote the hidden ``out/.rrd``; ``--save lap.mcap`` run
twice was refused for the bag the app itself wrote."""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

from conftest import cli
from fleetbags import still_bag

EXE = str(Path(sys.executable).parent / "r2d2-viz")


def test_a_bag_and_a_link_to_it_are_both_named(tmp_path: Path) -> None:
    alpha, beta = still_bag(tmp_path / "alpha"), still_bag(tmp_path / "beta")
    link = tmp_path / "latest"
    link.symlink_to(alpha)
    out = tmp_path / "out"
    result = cli("--bag", str(alpha), str(beta), str(link), "--save-dir", str(out))
    assert result.returncode == 0, result.stderr
    assert f"note: {link}: the same bag as {alpha} (a link to it); converted once" in result.stderr
    assert "r2d2-viz: 2 converted, 1 given twice →" in result.stderr  # 3 given, 3 accounted for
    assert sorted(p.name for p in out.iterdir()) == ["alpha.rbl", "alpha.rrd", "beta.rbl", "beta.rrd"]


def test_a_bag_given_as_dot_is_named_after_its_folder(tmp_path: Path) -> None:
    run = still_bag(tmp_path / "run")
    result = cli("--bag", ".", "--save-dir", "../out", cwd=run)
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["run.rbl", "run.rrd"]  # not ".rrd", ".rrd.rbl"


def test_a_bag_that_never_finishes_reading_is_named_and_named_again_at_ctrl_c(tmp_path: Path) -> None:
    """A FIFO nobody writes: opening it blocks, as a bag on a hung network mount does."""
    hung = tmp_path / "hung.mcap"
    os.mkfifo(hung)
    fine = still_bag(tmp_path / "fine")
    proc = subprocess.Popen(
        [EXE, "--bag", str(fine), str(hung), "--save-dir", str(tmp_path / "out"), "--jobs", "2"],
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        env={**os.environ, "R2D2_VIZ_FLEET_STALL_S": "2"},
    )
    assert proc.stderr is not None
    said = []
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if not select.select([proc.stderr], [], [], max(0.0, deadline - time.monotonic()))[0]:
            break  # nothing said in time: the assertion below fails instead of waiting for ever
        line = proc.stderr.readline()
        said.append(line)
        if f"still converting {hung} " in line or not line:  # once the other bag is done, it alone is named
            break
    try:
        assert said and f"still converting {hung} (Ctrl-C stops)" in said[-1], "".join(said)
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal sends Ctrl-C
        rest = proc.stderr.read()
        assert proc.wait(timeout=60) == 130, rest
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert f"not done (interrupted): {hung}" in rest, rest
    assert "1 converted" in rest and "1 not done (interrupted)" in rest, rest


def test_save_mcap_again_replaces_the_bag_it_wrote_and_nothing_else(tmp_path: Path) -> None:
    for _ in range(2):
        result = cli("--save", "lap.mcap", "--duration", "1", cwd=tmp_path)
        assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in (tmp_path / "lap.mcap").iterdir()) == ["lap.mcap", "metadata.yaml"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lap.mcap"]  # no temporary bag left beside it
    other = tmp_path / "notes.mcap"
    other.mkdir()
    (other / "mine.txt").write_text("not a bag")
    result = cli("--save", str(other), "--duration", "1")
    assert result.returncode == 2
    assert (
        result.stderr.strip()
        == f"error: --save {other}: a directory that is not a bag r2d2-viz wrote; not replacing it"
    )
    assert sorted(p.name for p in other.iterdir()) == ["mine.txt"]
