"""The summary of ``--compare``: figures worked by hand on a few numbers."""

from __future__ import annotations

import numpy as np

from r2d2_viz.run.differences import RunSummary, largest_difference, summary_lines

S = 1_000_000_000


def test_the_largest_difference_interpolates_the_other_run_onto_the_first_runs_times() -> None:
    t_ref, v_ref = np.array([0, 1, 2, 3]) * S, np.zeros(4)
    t_other, v_other = np.array([0.5, 2.5]) * S, np.array([1.0, 3.0])
    # inside [0.5 s, 2.5 s]: the first run's 1 s and 2 s; there the other is 1.5 and 2.5 (a line through its two)
    assert largest_difference(t_ref, v_ref, t_other.astype(np.int64), v_other) == (2.5, 2.0)
    assert largest_difference(t_ref, v_ref, np.array([9, 10]) * S, v_other) is None  # no overlap


def test_the_lines_name_what_one_run_has_alone_and_the_count_differences() -> None:
    a = RunSummary("a", 2.0, {"/joint_states": (50, 25.0), "/tf": (3, None)}, frozenset({"odom", "base"}))
    times = np.array([0, S, 2 * S])
    a.series["x"] = (times, np.array([0.0, 1.0, 2.0]))
    b = RunSummary("b", 1.5, {"/joint_states": (40, 26.0), "/extra": (5, 10.0)}, frozenset({"odom", "base", "cam"}))
    b.series["x"] = (times, np.array([0.0, 1.5, 2.0]))
    lines = summary_lines([a, b])
    assert "duration: a 2 s · b 1.5 s" in lines
    assert "topics only in a: /tf" in lines and "topics only in b: /extra" in lines
    assert "/joint_states: a 50 at 25 Hz · b 40 at 26 Hz (count difference: b -10)" in lines
    assert "/extra: a - · b 5 at 10 Hz (count difference: b +5)" in lines
    assert "frames only in b: cam" in lines
    assert "series x: a mean 1 max 2 · b mean 1.16666666667 max 2; largest difference from a: b 0.5 at 1 s" in lines
