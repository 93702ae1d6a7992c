"""A bag replay's progress on a terminal, as people know it from pip and rsync: one bar on stderr (rich), with the
percent of the bag replayed (by its time), MB/s and the time left — or, for a live replay, its position in the bag
(``12.3 / 150.0 s``), moving as the bag plays (not a window at a time) and left where Ctrl-C stopped it. Off a
terminal, nothing (the run's summary line says what was done).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, Protocol

from r2d2_viz.sources.plan import RunPlan
from r2d2_viz.sources.playback import Window

S = 1e9


class _Config(Protocol):
    @property
    def progress(self) -> bool: ...
    @property
    def live(self) -> bool: ...


def wanted() -> bool:
    """Whether a bar belongs on stderr (a terminal)."""
    return sys.stderr.isatty()


class _Bar:
    """The bar's task: each window done (bytes, rate) and, in a live replay, where the replay has got."""

    def __init__(self, bar: Any, task: Any, start: int, length: float) -> None:
        self.bar, self.task, self.start, self.length = bar, task, start, length
        self.done_bytes, self.began, self.shown = 0, time.monotonic(), ""

    def __call__(self, window: Window) -> None:
        self.done_bytes += window.nbytes
        rate = self.done_bytes / 1e6 / max(time.monotonic() - self.began, 1e-3)
        self.bar.update(self.task, mb=self.done_bytes / 1e6, rate=rate)
        self.at(window.end_ns)

    def at(self, t_ns: int) -> None:
        at = min(max(t_ns - self.start, 0) / S, self.length)
        if f"{at:.1f}" != self.shown or at == self.length:  # a 1 kHz run tells it more often than it can show
            self.shown = f"{at:.1f}"
            self.bar.update(self.task, completed=at, position=f"{at:.1f} / {self.length:.1f} s")


@contextmanager
def progress_bar(plan: RunPlan, config: _Config) -> Iterator[_Bar | None]:
    """The bar, a callback taking each window as it is done and (``at``) each time a live replay has got to
    (None: no bar wanted, or not a bag)."""
    if not config.progress or plan.replay is None:
        yield None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        Progress,
        TaskProgressColumn,
        TextColumn,
        TimeRemainingColumn,
    )

    start, end = plan.replay.span
    length = max(end - start, 1) / S
    name = plan.replay.bag.path.name
    console = Console(file=sys.stderr)
    if config.live:
        columns = (TextColumn("{task.description}"), BarColumn(), TextColumn("{task.fields[position]}"))
    else:
        columns = (  # type: ignore[assignment]
            TextColumn("{task.description}"),
            BarColumn(),
            TaskProgressColumn(),
            TextColumn("{task.fields[mb]:.0f} MB, {task.fields[rate]:.0f} MB/s"),
            TimeRemainingColumn(),
        )
    with Progress(*columns, console=console, transient=False) as bar:
        task = bar.add_task(name, total=length, position=f"0.0 / {length:.1f} s", mb=0.0, rate=0.0)
        yield _Bar(bar, task, start, length)


@contextmanager
def counting_bar(description: str, total: int, *, enabled: bool, unit: str = "frames") -> Iterator[Any]:
    """A bar of ``total`` steps (``--render``'s frames): the callable it yields takes one step; None: no bar."""
    if not enabled:
        yield None
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TextColumn(unit))
    with Progress(*columns, TimeRemainingColumn(), console=Console(file=sys.stderr), transient=False) as bar:
        task = bar.add_task(description, total=total)
        yield lambda: bar.advance(task)
