"""What differs between the runs of ``--compare``: topics present in some runs only, each topic's message count and
rate per run (the figures of ``--list``: :mod:`r2d2_viz.sources.system.topic_rates`), each run's duration, TF
frames present in some runs only, and for each plotted series its mean and max per run and its largest difference
from the first run at aligned times (the other run's values linearly interpolated onto the first run's times, where
they overlap). Pure numpy; no rerun import."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from r2d2_viz.arrays import F64
from r2d2_viz.errors import shown_in_line


@dataclass(frozen=True)
class RunSummary:
    """One run as the summary sees it; times on the shared timeline (ns since the run's alignment point)."""

    name: str
    duration_s: float
    topics: dict[str, tuple[int, float | None]]
    """Topic → (messages, rate in Hz or None); an ``.rrd`` run's entities and their rows."""
    frames: frozenset[str]
    series: dict[str, tuple[np.ndarray, F64]] = field(default_factory=dict)
    """Series name → (aligned times ns, values)."""


@dataclass(frozen=True)
class SeriesDifference:
    name: str
    stats: dict[str, tuple[float, float] | None]
    """Run → (mean, max) of its values; None: the run has no such series."""
    largest: dict[str, tuple[float, float] | None]
    """Run (but the first) → (largest |run − first|, at that aligned time in s); None: no overlap."""


def largest_difference(t_ref: np.ndarray, v_ref: F64, t_other: np.ndarray, v_other: F64) -> tuple[float, float] | None:
    """The largest ``|other − ref|`` at ``ref``'s times within ``other``'s span (``other`` linearly interpolated),
    and that time (s); None when the spans do not overlap."""
    if not len(t_ref) or not len(t_other):
        return None
    inside = (t_ref >= t_other[0]) & (t_ref <= t_other[-1])
    if not inside.any():
        return None
    at = t_ref[inside].astype(np.float64)
    diff = np.abs(np.interp(at, t_other.astype(np.float64), v_other) - v_ref[inside])
    k = int(np.argmax(diff))
    return float(diff[k]), float(at[k]) / 1e9


def series_differences(runs: Sequence[RunSummary]) -> list[SeriesDifference]:
    """Every series any run plotted, with its figures (:class:`SeriesDifference`), in name order."""
    names = sorted({name for run in runs for name in run.series})
    first = runs[0]
    out = []
    for name in names:
        stats: dict[str, tuple[float, float] | None] = {}
        largest: dict[str, tuple[float, float] | None] = {}
        for run in runs:
            found = run.series.get(name)
            stats[run.name] = (float(np.mean(found[1])), float(np.max(found[1]))) if found and len(found[1]) else None
            if run is not first:
                ref = first.series.get(name)
                largest[run.name] = largest_difference(*ref, *found) if ref is not None and found else None
        out.append(SeriesDifference(name, stats, largest))
    return out


def _rate(rate: float | None) -> str:
    return f" at {rate:.4g} Hz" if rate is not None else ""


def summary_lines(runs: Sequence[RunSummary]) -> list[str]:
    """The summary as lines of text (each name shown on its line: :func:`shown_in_line`)."""
    names = [r.name for r in runs]
    lines = [f"runs: {', '.join(names)} (the first is the reference; times are since each run's alignment point)"]
    lines.append("duration: " + " · ".join(f"{r.name} {r.duration_s:.6g} s" for r in runs))
    topics = sorted({t for r in runs for t in r.topics})
    for run in runs:
        only = [t for t in topics if t in run.topics and sum(t in r.topics for r in runs) < len(runs)]
        if only:
            lines.append(f"topics only in {run.name}" + (" (and some other runs)" if len(runs) > 2 else "") + ": ")
            lines[-1] += ", ".join(only)
    for topic in topics:
        cells = []
        counts = []
        for run in runs:
            found = run.topics.get(topic)
            cells.append(f"{run.name} {found[0]}{_rate(found[1])}" if found else f"{run.name} -")
            counts.append(found[0] if found else 0)
        delta = ", ".join(f"{r.name} {c - counts[0]:+d}" for r, c in zip(runs[1:], counts[1:], strict=True))
        lines.append(f"{topic}: " + " · ".join(cells) + f" (count difference: {delta})")
    frames = sorted({f for r in runs for f in r.frames})
    for run in runs:
        only = [f for f in frames if f in run.frames and sum(f in r.frames for r in runs) < len(runs)]
        if only:
            lines.append(f"frames only in {run.name}: " + ", ".join(only))
    for diff in series_differences(runs):
        cells = [
            f"{run} mean {s[0]:.12g} max {s[1]:.12g}" if s is not None else f"{run} -" for run, s in diff.stats.items()
        ]
        largest = [
            f"{run} {d[0]:.12g} at {d[1]:.6g} s" if d is not None else f"{run} -" for run, d in diff.largest.items()
        ]
        lines.append(f"series {diff.name}: " + " · ".join(cells) + f"; largest difference from {names[0]}: ")
        lines[-1] += ", ".join(largest)
    return [shown_in_line(line) for line in lines]
