"""Run names, ``--offset`` values and alignment points of ``--compare`` (by hand: a few nanoseconds)."""

from __future__ import annotations

from pathlib import Path

import pytest

from r2d2_viz.errors import UsageError
from r2d2_viz.run.alignment import Alignment, alignments, parse_offsets, run_name, run_names


def test_runs_are_named_after_their_bags_uniquely_and_safely() -> None:
    paths = [Path("/x/day1/run.mcap"), Path("/y/run"), Path("/z/run.db3"), Path("/w/my run!.bag"), Path("r.rrd")]
    assert run_names(paths) == ["run", "run-2", "run-3", "my_run", "r"]
    assert run_name(Path("/weird/\x1b[2J")) == "2J"
    assert run_name(Path("...")) == "run"


def test_offsets_name_a_run_and_a_finite_number_of_seconds() -> None:
    assert parse_offsets(["b=0.5", "a=-1"], ["a", "b"]) == {"b": 0.5, "a": -1.0}
    for bad, says in (("b", "expected NAME=SECONDS"), ("c=1", "no run named 'c'"), ("b=inf", "'inf' is not")):
        with pytest.raises(UsageError, match=says):
            parse_offsets([bad], ["a", "b"])


def test_a_run_is_shifted_to_the_time_since_its_alignment_point_plus_its_offset() -> None:
    starts = {"a": 1_000, "b": 5_000}
    firsts = {"a": 1_300, "b": None}
    assert alignments(["a", "b"], starts, None, {"b": 0.000_002}, None) == {
        "a": Alignment(1_000),
        "b": Alignment(5_000, 0.000_002),
    }
    assert Alignment(5_000, 0.000_002).shift_ns() == 2_000 - 5_000
    with pytest.raises(UsageError, match="run b has no message on that topic"):
        alignments(["a", "b"], starts, firsts, {}, "/go")
    assert alignments(["a"], starts, firsts, {}, "/go") == {"a": Alignment(1_300)}
