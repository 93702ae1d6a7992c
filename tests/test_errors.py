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
