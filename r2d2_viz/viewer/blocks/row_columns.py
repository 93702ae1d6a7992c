"""Every other display's rows as columns (issue 46, item 3): IMU axes and plots, log lines, diagnostics states,
markers, paths, poses and their arrays, text, fixes and numbers were one ``rec.log`` per message (~140 µs each).

:class:`RowColumns` stands in for the recording where :func:`r2d2_viz.viewer.displays.log_decoded` logs: each
``log`` keeps its row — the very components ``rec.log`` would send (each archetype's non-empty batches, the first of
a descriptor given twice) — on its entity's run, at the time last set; a run goes out as one ``rr.send_columns``
per stretch of rows with the same components, a row per message at its time, rows in the order they were logged.

What keeps the recording the same as per-message logs: static rows go at once (they have no time); a ``Clear``
sends the runs it covers first and is logged on its own (a recursive clear hides what its entity and those below it
had at its time, up to its own row: rows after it at the same time must come after it); the display feed sends
an entity's run before it logs that entity another way (its images' and clouds' runs, the anchors of a topic's
entities, a map) and leaves the recording's time where the last row left it. What Rerun stamps on ``rec.log``
rows and not on columns — the ``log_time`` / ``log_tick`` timelines — is not there, as for the other columns.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.viewer.columns import send, time_array
from r2d2_viz.viewer.displays import Clock, set_time

RUN_ROWS = 4096
"""The most rows an entity's run holds before it is sent."""
HELD_ROWS = 65_536
HELD_BYTES = 16 << 20
"""A batch run keeps its runs across windows, all sent once they hold this many rows or bytes in all (a chunk per
window and entity made Rerun keep ~3 kB per chunk until the footer, as for the image and cloud runs; a map, a
mesh or a video sample is megabytes)."""


@dataclass
class _Group:
    """Consecutive rows of one entity with the same components."""

    descriptors: tuple[rr.ComponentDescriptor, ...]
    times_ns: list[int] = field(default_factory=list)
    arrays: list[list[pa.Array]] = field(default_factory=list)
    """Per descriptor, each row's array of instances."""
    nbytes: int = 0


class RowColumns:
    """Rows logged through :meth:`log` (at the time :meth:`set_time` gave), held per entity until :meth:`send`;
    ``hold``: a batch run, whose runs stay across windows (a live one sends at the end of each)."""

    def __init__(self, rec: rr.RecordingStream, timeline: str, clock: Clock, *, hold: bool = False) -> None:
        self.rec, self.timeline, self.clock, self.hold = rec, timeline, clock, hold
        self.runs: dict[str, list[_Group]] = {}
        self.now: int | None = None
        self.held = self.held_bytes = 0

    def at(self, time_ns: int) -> None:
        """What :func:`~r2d2_viz.viewer.displays.set_time` calls: the time of the rows logged next."""
        self.now = time_ns

    def log(self, entity: str, *archetypes: Any, static: bool = False) -> None:
        """One row on ``entity`` at the time set (a static one, or a ``Clear``: logged at once, in order)."""
        if static:
            self.rec.log(entity, *archetypes, static=True)
            return
        if any(isinstance(a, rr.Clear) for a in archetypes):
            self.send(entity)
            self._release_time()
            self.rec.log(entity, *archetypes)
            return
        assert self.now is not None, "rows need a time"
        batches = [b for a in archetypes for b in a.as_component_batches()]
        descriptors: list[rr.ComponentDescriptor] = []
        arrays: list[pa.Array] = []
        for batch in batches:
            descriptor, array = batch.component_descriptor(), batch.as_arrow_array()
            if array is not None and descriptor not in descriptors:  # as rec.log: the first of a descriptor
                descriptors.append(descriptor)
                arrays.append(array)
        self.add(entity, tuple(descriptors), arrays)

    def add(self, entity: str, descriptors: tuple[rr.ComponentDescriptor, ...], arrays: list[pa.Array]) -> None:
        """A row of prebuilt component arrays (one array of instances per descriptor) at the time set."""
        assert self.now is not None, "rows need a time"
        groups = self.runs.setdefault(entity, [])
        if not groups or groups[-1].descriptors != descriptors:
            groups.append(_Group(descriptors, arrays=[[] for _ in descriptors]))
        group = groups[-1]
        before = group.nbytes
        group.times_ns.append(self.now)
        for column, array in zip(group.arrays, arrays, strict=True):
            column.append(array)
            group.nbytes += array.nbytes
        self.held += 1
        self.held_bytes += group.nbytes - before
        if self.held >= HELD_ROWS or self.held_bytes >= HELD_BYTES:
            self.send()
        elif len(group.times_ns) >= RUN_ROWS:
            self.send(entity)

    def send(self, *entities: str) -> None:
        """Send the runs of ``entities`` and of the entities below them (every run when none is named)."""
        if not self.runs:
            return
        below = tuple(e + "/" for e in entities)
        names = [e for e in self.runs if e in entities or e.startswith(below)] if entities else list(self.runs)
        for name in names:
            for group in self.runs.pop(name):
                self.held -= len(group.times_ns)
                self.held_bytes -= group.nbytes
                times = time_array(np.array(group.times_ns, dtype=np.int64), self.clock)
                columns = [(d, _column(rows)) for d, rows in zip(group.descriptors, group.arrays, strict=True)]
                send(self.rec, name, self.timeline, times, columns)

    def window_end(self, *, everything: bool = False) -> None:
        """The end of a window: a live run (or the run's end) sends what it holds; the recording's time is left
        where the last row left it."""
        if everything or not self.hold:
            self.send()
        self._release_time()

    def _release_time(self) -> None:
        if self.now is not None:
            set_time(self.rec, self.timeline, self.now, self.clock)


def _column(rows: list[pa.Array]) -> pa.Array:
    """Each row's array of instances as one list array, a row per list."""
    values = rows[0] if len(rows) == 1 else pa.concat_arrays(rows)
    offsets = np.zeros(len(rows) + 1, dtype=np.int32)
    np.cumsum([len(r) for r in rows], out=offsets[1:])
    return pa.Array.from_buffers(pa.list_(values.type), len(rows), [None, pa.py_buffer(offsets)], children=[values])
