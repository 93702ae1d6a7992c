"""Read an .rrd back with Rerun's own reader, as plain Python/numpy, for assertions."""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from rerun.chunk import RrdReader

IGNORED = {"rerun.controls.RowId", "log_time", "log_tick"}


@dataclass
class Rows:
    """All rows logged to one entity: static ones, and temporal ones with their ``time`` in ns."""

    static: dict[str, list[Any]] = field(default_factory=lambda: defaultdict(list))
    times: list[int] = field(default_factory=list)
    temporal: dict[str, list[Any]] = field(default_factory=lambda: defaultdict(list))


def read_recording(path: str | Path) -> dict[str, Rows]:
    """Entity path → its rows. Temporal rows are sorted by the ``time`` timeline."""
    reader = RrdReader(path)
    entities: dict[str, Rows] = defaultdict(Rows)
    for chunk in reader.stream(store=reader.recordings()[0]):
        batch = chunk.to_record_batch()
        rows = entities[chunk.entity_path]
        names = [f.name for f in batch.schema]
        columns = {name: batch.column(i) for i, name in enumerate(names) if name not in IGNORED}
        if chunk.is_static:
            for name, column in columns.items():
                rows.static[name].extend(column.to_pylist())
            continue
        time = columns.pop("time", None)
        if time is None:
            continue
        n_before = len(rows.times)
        rows.times.extend(time.cast("int64").to_pylist())
        for name, column in columns.items():
            values = rows.temporal[name]
            values.extend([None] * (n_before - len(values)))
            values.extend(column.to_pylist())
    for rows in entities.values():
        order = np.argsort(rows.times, kind="stable")
        rows.times = [rows.times[i] for i in order]
        for name, values in list(rows.temporal.items()):
            values.extend([None] * (len(order) - len(values)))
            rows.temporal[name] = [values[i] for i in order]
    return dict(entities)


def blueprint_components(path: str | Path) -> dict[str, dict[str, Any]]:
    """Entity path → {component: value} of the (first) blueprint store in an .rrd or .rbl file."""
    reader = RrdReader(path)
    out: dict[str, dict[str, Any]] = defaultdict(dict)
    for chunk in reader.stream(store=reader.blueprints()[0]):
        batch = chunk.to_record_batch()
        for i, f in enumerate(batch.schema):
            if f.name not in IGNORED and f.name != "blueprint":
                out[chunk.entity_path][f.name] = batch.column(i).to_pylist()[-1]
    return dict(out)


def tf_by_child(recording: dict[str, Rows], entity: str = "/tf") -> dict[str, Rows]:
    """The rows of a ``/tf``-like entity (several child frames per time) split by child frame."""
    out: dict[str, Rows] = defaultdict(Rows)
    rows = recording.get(entity)
    if rows is None:
        return {}
    for i, child in enumerate(rows.temporal["Transform3D:child_frame"]):
        mine = out[child[0]]
        mine.times.append(rows.times[i])
        for name, values in rows.temporal.items():
            mine.temporal[name].append(values[i])
    return dict(out)
