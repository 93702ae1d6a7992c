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

from r2d2_viz.msgs.shapes import Shape
from r2d2_viz.viewer.blocks.row_items import Builder, row_of
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
    builders: tuple[Builder, ...] | None
    """How each column is built from its rows' numbers (:mod:`~r2d2_viz.viewer.blocks.row_items`); None: the rows
    are Arrow arrays of instances already (an archetype's)."""
    times_ns: list[int] = field(default_factory=list)
    arrays: list[list[Any]] = field(default_factory=list)
    """Per descriptor, each row's instances."""
    nbytes: int = 0


class RowColumns:
    """Rows logged through :meth:`log` (at the time :meth:`set_time` gave), held per entity until :meth:`send`;
    ``hold``: a batch run, whose runs stay across windows (a live one sends at the end of each)."""

    def __init__(self, rec: rr.RecordingStream, timeline: str, clock: Clock, *, hold: bool = False) -> None:
        self.rec, self.timeline, self.clock, self.hold = rec, timeline, clock, hold
        self.runs: dict[str, list[_Group]] = {}
        self.now: int | None = None
        self._moved = False
        self.held = self.held_bytes = 0

    def at(self, time_ns: int) -> None:
        """What :func:`~r2d2_viz.viewer.displays.set_time` calls: the time of the rows logged next."""
        self.now, self._moved = time_ns, True

    def log(self, entity: str, first: rr.AsComponents, *extra: rr.AsComponents, static: bool = False) -> None:
        """One row on ``entity`` at the time set (a static one, or a ``Clear``: logged at once, in order)."""
        archetypes = (first, *extra)
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

    def take(self, entity: str, item: Shape, frame: str) -> bool:
        """Whether ``item`` (drawn in ``frame``) was taken as a row of numbers (:func:`row_of`), not archetypes."""
        row = row_of(item, frame)
        if row is None:
            return False
        self.add(entity, tuple(d for d, _, _ in row), [v for _, _, v in row], tuple(b for _, b, _ in row))
        return True

    def add(
        self,
        entity: str,
        descriptors: tuple[rr.ComponentDescriptor, ...],
        values: list[Any],
        builders: tuple[Builder, ...] | None = None,
    ) -> None:
        """A row at the time set: an array of instances per descriptor (Arrow arrays; or numbers ``builders`` make
        columns of)."""
        assert self.now is not None, "rows need a time"
        groups = self.runs.setdefault(entity, [])
        if not groups or groups[-1].descriptors != descriptors or groups[-1].builders != builders:
            groups.append(_Group(descriptors, builders, arrays=[[] for _ in descriptors]))
        group = groups[-1]
        before = group.nbytes
        group.times_ns.append(self.now)
        for column, value in zip(group.arrays, values, strict=True):
            column.append(value)
        if builders is None:
            group.nbytes += sum(a.get_total_buffer_size() for a in values)
        self.held += 1
        self.held_bytes += group.nbytes - before
        if self.held >= HELD_ROWS or self.held_bytes >= HELD_BYTES:
            self.send()
        elif len(group.times_ns) >= RUN_ROWS:
            self.send(entity)

    def add_block(
        self, entity: str, descriptors: tuple[rr.ComponentDescriptor, ...], times_ns: np.ndarray, columns: list[Any]
    ) -> None:
        """Many rows of ``entity`` at once (a block decoder's, :mod:`~r2d2_viz.viewer.blocks.marker_columns`):
        per descriptor, its instances as one Arrow array and each row's count, as a ``Builder`` makes them."""
        groups = self.runs.setdefault(entity, [])
        chunks = (_chunks,) * len(descriptors)
        if not groups or groups[-1].descriptors != descriptors or groups[-1].builders != chunks:
            groups.append(_Group(descriptors, chunks, arrays=[[] for _ in descriptors]))
        group = groups[-1]
        group.times_ns.extend(times_ns.tolist())
        for column, chunk in zip(group.arrays, columns, strict=True):
            column.append(chunk)
        self.held += len(times_ns)
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
                builders = group.builders or (_concatenated,) * len(group.descriptors)
                columns = [
                    (d, _column(*b(v))) for d, b, v in zip(group.descriptors, builders, group.arrays, strict=True)
                ]
                send(self.rec, name, self.timeline, times, columns)

    def window_end(self, *, everything: bool = False) -> None:
        """The end of a window: a live run (or the run's end) sends what it holds; the recording's time is left
        where the last row left it."""
        if everything or not self.hold:
            self.send()
        self._release_time()

    def _release_time(self) -> None:
        """The recording's time where the rows logged since the last release left it (logging them would have)."""
        if self._moved and self.now is not None:
            set_time(self.rec, self.timeline, self.now, self.clock)
        self._moved = False


def _concatenated(rows: list[pa.Array]) -> tuple[pa.Array, list[int]]:
    """Rows of Arrow arrays of instances (an archetype's) → their instances as one array, and each row's count."""
    return (rows[0] if len(rows) == 1 else pa.concat_arrays(rows)), [len(r) for r in rows]


def _chunks(chunks: list[tuple[pa.Array, Any]]) -> tuple[pa.Array, list[int] | np.ndarray]:
    """Blocks of rows (instances, each row's count) → one array of instances and every row's count."""
    arrays = [a for a, _ in chunks]
    values = arrays[0] if len(arrays) == 1 else pa.concat_arrays(arrays)
    return values, np.concatenate([np.asarray(n, dtype=np.int64) for _, n in chunks])


def _column(values: pa.Array, lengths: list[int] | np.ndarray) -> pa.Array:
    """``values`` cut into a list a row, of ``lengths``: a component column."""
    offsets = np.zeros(len(lengths) + 1, dtype=np.int32)
    np.cumsum(lengths, out=offsets[1:])
    return pa.Array.from_buffers(pa.list_(values.type), len(lengths), [None, pa.py_buffer(offsets)], children=[values])
