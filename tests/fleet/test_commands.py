"""The fleet's command line (issue 25): on a terminal one overall progress bar (bags, bytes, ETA) — the real CLI
on a pseudo-terminal — and off one the summary line alone (tests/fleet/test_convert.py)."""

from __future__ import annotations

from pathlib import Path

from fleetbags import still_bag
from terminal import on_a_terminal


def test_one_overall_progress_bar_on_a_terminal(tmp_path: Path) -> None:
    bags = [still_bag(tmp_path / f"bag{k}") for k in range(3)]
    code, screen = on_a_terminal("--bag", *map(str, bags), "--save-dir", str(tmp_path / "out"), "--jobs", "2")
    assert code == 0, screen
    assert "converting" in screen and "/3 bags" in screen and "ETA" in screen
    assert screen.count("converting") >= 1 and "bag0" not in screen.split("r2d2-viz:")[0]  # one bar, not per bag
    assert "3 converted" in screen
