"""``r2d2-viz --compare``'s flags, as a user types them (the installed CLI): listed by ``--help``; what cannot go
with a comparison is one line and exit 2, before anything is read."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import cli


def test_help_lists_the_comparison_flags() -> None:
    out = cli("--help").stdout
    for flag in ("--compare RUN [RUN ...]", "--align TOPIC", "--offset NAME=SECONDS", "--side-by-side"):
        assert flag in out


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--bag", "c"], "--compare takes its runs as its arguments; it cannot be combined with --bag"),
        (["--motion", "sweep"], "--compare takes its runs as its arguments; it cannot be combined with --motion"),
        (["--summary", "out.csv"], "--compare … --summary prints the differences; it writes no file ('out.csv')"),
        (["--save", "out.mcap"], "--save out.mcap: a comparison is a recording: give a .rrd file"),
        (["--serve", "--spawn"], "choose one live sink, not --spawn and --serve"),
    ],
)
def test_what_cannot_go_with_a_comparison_is_one_line_and_exit_2(tmp_path: Path, args: list[str], says: str) -> None:
    result = cli("--compare", str(tmp_path / "a"), str(tmp_path / "b"), *args, cwd=tmp_path, timeout=60)
    assert (result.returncode, result.stderr.splitlines(), result.stdout) == (2, [f"error: {says}"], "")
    assert not list(tmp_path.iterdir())  # nothing written
