"""``r2d2-viz --compare A B [C…]``: several runs (bags, or ``.rrd`` recordings the app wrote) in one recording.

Each bag is first replayed by the ordinary pipeline (:func:`r2d2_viz.runner.run`, with the run's ``--plot``,
``--rviz`` and other flags) into a temporary ``.rrd``; then every run's chunks go to the one recording under
``/runs/<name>``, shifted onto the shared timeline (:mod:`r2d2_viz.run.alignment`), their frames renamed, the
others' robots as ghosts (:mod:`r2d2_viz.viewer.compare.merge`); the differences
(:mod:`r2d2_viz.run.differences`) are printed (``--summary``) or shown in the layout."""

from __future__ import annotations

import dataclasses
import math
import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from r2d2_viz.errors import UsageError, shown_in_line
from r2d2_viz.pacing import keep_serving
from r2d2_viz.run.alignment import Alignment, alignments, parse_offsets, run_names
from r2d2_viz.run.differences import RunSummary, summary_lines
from r2d2_viz.runner import RunConfig, run
from r2d2_viz.signals import sigterm_raises
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.system.topic_rates import topic_rates
from r2d2_viz.viewer.compare.layout import compare_blueprint
from r2d2_viz.viewer.compare.merge import RunFacts, RunStyle, blueprint_view, recording_chunks, send_run
from r2d2_viz.viewer.compare.scene import anchor, log_summary, tint
from r2d2_viz.viewer.files.whole import flush_file, rrd_complete, saved_rrd
from r2d2_viz.viewer.sinks import SinkConfig, close_recording, open_recording

SIDE_BY_SIDE_MIN_M = 1.0
"""``--side-by-side``: runs this far apart along y at least (else 0.6 × the first run's camera distance)."""


@dataclass(frozen=True)
class CompareConfig:
    inputs: tuple[Path, ...]
    base: RunConfig = dataclasses.field(default_factory=RunConfig)
    """Every run's flags (``--plot``, ``--rviz``, ``--urdf``…) and the comparison's sink."""
    align: str | None = None
    offsets: tuple[str, ...] = ()
    side_by_side: bool = False
    summary_only: bool = False


@dataclass
class _Run:
    name: str
    path: Path
    rrd: Path | None
    """The run as a recording (a bag's: once replayed)."""
    start_ns: int
    end_ns: int
    topics: dict[str, tuple[int, float | None]]
    firsts: dict[str, int]
    facts: RunFacts = dataclasses.field(default_factory=RunFacts)

    @property
    def recorded(self) -> Path:
        """The run's recording (once a bag's is made)."""
        if self.rrd is None:
            raise RuntimeError(f"{self.name}: not replayed yet")
        return self.rrd


@dataclass
class CompareResult:
    names: list[str]
    summary: list[str]
    saved: Path | None
    interrupted: bool = False


def compare(config: CompareConfig, on_ready: Callable[[str], None] | None = None) -> CompareResult:
    """The comparison of ``config.inputs``; raises R2d2VizError for bad input, never leaves a half-written file."""
    if len(config.inputs) < 2:
        raise UsageError(f"--compare needs two runs or more, got {len(config.inputs)}")
    names = run_names(config.inputs)
    offsets = parse_offsets(config.offsets, names)
    runs = [_inspect(path, name) for path, name in zip(config.inputs, names, strict=True)]
    if config.align is not None and not any(config.align in r.firsts for r in runs):
        raise UsageError(f"--align {shown_in_line(config.align)}: no run has that topic")
    aligned = alignments(
        names,
        {r.name: r.start_ns for r in runs},
        {r.name: r.firsts.get(config.align) for r in runs} if config.align is not None else None,
        offsets,
        config.align,
    )
    with tempfile.TemporaryDirectory(prefix="r2d2-viz-compare-") as scratch:
        for r in runs:
            if r.rrd is None:
                r.rrd = _convert(r, config, Path(scratch))
                r.facts = _facts(r.rrd)
        lines = summary_lines([_summary(r, aligned[r.name]) for r in runs])
        if config.summary_only:
            return CompareResult(names, lines, None)
        return _record(config, runs, aligned, lines, on_ready)


def _inspect(path: Path, name: str) -> _Run:
    """A run as its input says it: a bag's span and its topics' counts, rates and first times (nothing decoded), or
    an ``.rrd`` read once (its entities and their rows instead)."""
    if path.suffix == ".rrd":
        if not path.is_file() or not rrd_complete(path):
            raise UsageError(f"--compare {shown_in_line(str(path))}: not a whole .rrd recording")
        facts = _facts(path)
        if facts.first_ns is None or facts.last_ns is None:
            raise UsageError(f"--compare {shown_in_line(str(path))}: the recording has nothing on its timeline")
        topics: dict[str, tuple[int, float | None]] = {e: (n, None) for e, n in facts.entities.items()}
        return _Run(name, path, path, facts.first_ns, facts.last_ns, topics, dict(facts.firsts), facts)
    with open_bag(path) as bag:
        span = bag.span
        if span is None:
            raise UsageError(f"--compare {shown_in_line(str(path))}: the bag has no messages")
        rates = topic_rates(bag)
    counts: dict[str, tuple[int, float | None]] = {t: (r.count, r.rate_hz) for t, r in rates.items()}
    return _Run(name, path, None, span[0], span[1], counts, {t: r.first_ns for t, r in rates.items()})


def _convert(r: _Run, config: CompareConfig, scratch: Path) -> Path:
    """The bag replayed by the ordinary pipeline into ``scratch/<name>.rrd``."""
    target = scratch / f"{r.name}.rrd"
    with sigterm_raises():
        run(dataclasses.replace(config.base, bag=r.path, sink=SinkConfig(save=target), realtime=False))
    return target


def _facts(path: Path) -> RunFacts:
    facts = RunFacts()
    for chunk in recording_chunks(path):
        facts.read(chunk, chunk.to_record_batch())
    return facts


def _summary(r: _Run, alignment: Alignment) -> RunSummary:
    shift = alignment.shift_ns()
    series = {name: (times + shift, values) for name, (times, values) in r.facts.named_series().items()}
    return RunSummary(r.name, (r.end_ns - r.start_ns) / 1e9, r.topics, frozenset(r.facts.frames), series)


def _spacing(eye: dict[str, list[float]]) -> float:
    if len(eye.get("position", ())) == 3 and len(eye.get("look_target", ())) == 3:
        distance = float(np.linalg.norm(np.subtract(eye["position"], eye["look_target"])))
        if math.isfinite(distance):
            return max(SIDE_BY_SIDE_MIN_M, 0.6 * distance)
    return SIDE_BY_SIDE_MIN_M


def _record(
    config: CompareConfig,
    runs: list[_Run],
    aligned: dict[str, Alignment],
    lines: list[str],
    on_ready: Callable[[str], None] | None,
) -> CompareResult:
    views = [blueprint_view(r.recorded) for r in runs]
    hidden = {r.name: v.hidden for r, v in zip(runs, views, strict=True)}
    blueprint = compare_blueprint([r.name for r in runs], config.base.plots, views[0].eye, hidden)
    sink = config.base.sink
    save = sink.save
    tmp = save.with_name(f".{save.name}.{os.getpid()}.partial") if save is not None else None
    spacing = _spacing(views[0].eye) if config.side_by_side else 0.0
    with saved_rrd(tmp, save), sigterm_raises():
        recording = open_recording(sink, save_to=tmp, on_ready=on_ready, blueprint=blueprint)
        try:
            for k, (r, view) in enumerate(zip(runs, views, strict=True)):
                style = RunStyle(r.name, aligned[r.name].shift_ns(), tint(k))
                if view.frame is not None:
                    anchor(recording.rec, style, view.frame, (0.0, k * spacing, 0.0))
                send_run(recording.rec, r.recorded, style)
                flush_file(recording.rec, tmp)
            log_summary(recording.rec, lines)
            keep_serving(sink.serve, lambda: flush_file(recording.rec, tmp))
        finally:
            close_recording(recording)
    return CompareResult([r.name for r in runs], lines, save)
