"""One hierarchy: every expected failure is an R2d2VizError, which the CLI turns into one line and exit 2."""

from __future__ import annotations

import pytest

import r2d2_viz.errors as errors
from r2d2_viz.cli import EXIT_BAD_INPUT, main

KINDS = [c for c in vars(errors).values() if isinstance(c, type) and issubclass(c, Exception)]


def test_every_error_is_an_r2d2viz_error() -> None:
    assert len(KINDS) >= 5 and all(issubclass(kind, errors.R2d2VizError) for kind in KINDS)


@pytest.mark.parametrize("kind", KINDS, ids=lambda k: k.__name__)
def test_the_cli_says_one_line_and_exits_2(kind, monkeypatch, capsys) -> None:
    def fail(*args, **kwargs):
        raise kind(f"thing.urdf: the {kind.__name__} problem")

    monkeypatch.setattr("r2d2_viz.runner.run", fail)
    assert main(["--headless"]) == EXIT_BAD_INPUT
    assert capsys.readouterr().err == f"error: thing.urdf: the {kind.__name__} problem\n"


def test_one_line_collapses_a_library_message_for_a_warning() -> None:
    assert errors.one_line(ValueError("line 3:\n  bad   value\n")) == "line 3: bad value"  # by hand
    assert errors.one_line(KeyError()) == "KeyError"  # an empty message still says something
    assert len(errors.one_line(ValueError("x" * 500))) == 200


def test_listed_shows_a_few_names_and_counts_the_rest() -> None:
    names = [f"/t{k}" for k in range(78)]
    assert errors.listed(names) == "/t0, /t1, /t2, /t3, /t4 and 73 more"  # by hand
    assert errors.listed(names[:6]) == "/t0, /t1, /t2, /t3, /t4, /t5"  # "and 1 more" would be no shorter
    assert errors.listed(names[:7]) == "/t0, /t1, /t2, /t3, /t4 and 2 more"
    assert errors.listed([]) == "" and errors.listed(["a"]) == "a"
    assert errors.listed(iter(names), first=2) == "/t0, /t1 and 76 more"


def test_listed_keeps_a_line_short_whatever_the_names() -> None:
    long = [f"/gazebo/link_{k:02d}/diagnostics_with_a_long_name (std_msgs/msg/String)" for k in range(70)]  # 67 chars
    assert errors.listed(long) == f"{long[0]}, {long[1]} and 68 more"  # 2 x 67 + 2 fit in 140, 3 would not
    hostile = ["/" + "x" * 5000, "/y"]
    assert errors.listed(hostile) == "/" + "x" * 98 + "…, /y"  # a name is cut at 100 characters
    assert errors.listed(["/" + "x" * 5000] * 3) == "/" + "x" * 98 + "… and 2 more"


def test_a_stderr_line_is_at_most_300_characters_and_keeps_its_end() -> None:
    line = "warning: bag: /scan: " + "z" * 1000 + " (further problems on this topic are counted)"
    short = errors.stderr_line(line)
    assert len(short) == 300 and short.startswith("warning: bag: /scan: zzz") and "…" in short
    assert short.endswith(" (further problems on this topic are counted)")
    assert errors.stderr_line("a\n" + "b" * 400).split("\n")[0] == "a"  # line by line
    assert errors.stderr_line("short") == "short"


def test_warnings_from_two_threads_stay_whole_lines(capsys: pytest.CaptureFixture[str]) -> None:
    """A bag's reader thread and the run warn at once: every line whole (a CI run once showed two warnings run
    into one line, 'and 39 morewarning: …', when each was print()ed)."""
    import threading

    from r2d2_viz.errors import warn

    def many(who: str) -> None:
        for k in range(300):
            warn(f"{who} {k} " + "x" * 200)

    threads = [threading.Thread(target=many, args=(who,)) for who in ("reader", "run")]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 600 and all(line.startswith("warning: ") and line.endswith("x" * 200) for line in lines)


def test_control_characters_are_shown_not_sent(capsys: pytest.CaptureFixture[str]) -> None:
    """A frame name from a bag with escape sequences (cursor up, erase line, set the title, a carriage return):
    the warning shows them as escapes, one line, and the lines above stay as they were."""
    frame = "base\x1b[2A\x1b[2Kr2d2-viz: all fine\x1b]0;pwned\x07\r\x9b"
    errors.warn(f"no transform to {frame}")
    err = capsys.readouterr().err
    assert err == "warning: no transform to base\\x1b[2A\\x1b[2Kr2d2-viz: all fine\\x1b]0;pwned\\x07\\x0d\\x9b\n"
    assert errors.shown("tab\tand\nnewline") == "tab\tand\nnewline"  # the two a line may hold


def test_a_name_in_a_listing_stays_on_its_line() -> None:
    # by hand: every control character, tab and newline included, as its \x escape
    assert errors.shown_in_line("node\n/fake\tx\x1b[2J\x00") == "node\\x0a/fake\\x09x\\x1b[2J\\x00"
