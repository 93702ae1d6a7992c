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


def blueprint_components(path: str | Path, which: int = 0) -> dict[str, dict[str, Any]]:
    """Entity path → {component: value} of the (first) blueprint store in an .rrd or .rbl file (``which``: another
    of them, in the reader's order — not the order they were sent: see :func:`blueprint_count`)."""
    reader = RrdReader(path)
    out: dict[str, dict[str, Any]] = defaultdict(dict)
    for chunk in reader.stream(store=reader.blueprints()[which]):
        batch = chunk.to_record_batch()
        for i, f in enumerate(batch.schema):
            if f.name not in IGNORED and f.name != "blueprint":
                out[chunk.entity_path][f.name] = batch.column(i).to_pylist()[-1]
    return dict(out)


def blueprint_count(path: str | Path) -> int:
    """How many blueprint stores an .rrd file holds (a live run sends a new layout when a topic needs a view)."""
    return len(RrdReader(path).blueprints())


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


def pose(translation: list[float] | None, xyzw: list[float] | None) -> np.ndarray:
    from reference import quat_xyzw_to_matrix

    T = np.eye(4)
    if xyzw is not None:
        T[:3, :3] = quat_xyzw_to_matrix(xyzw)
    if translation is not None:
        T[:3, 3] = translation
    return T


def static_edges(recording: dict[str, Rows]) -> dict[str, tuple[str, np.ndarray]]:
    """Child frame → (parent frame, T_parent_child) of every static ``Transform3D`` naming its frames."""
    edges: dict[str, tuple[str, np.ndarray]] = {}
    for rows in recording.values():
        child = rows.static.get("Transform3D:child_frame")
        if child:
            T = pose(
                rows.static["Transform3D:translation"][-1][0],
                (rows.static.get("Transform3D:quaternion") or [[None]])[-1][0],
            )
            edges[child[-1][0]] = (rows.static["Transform3D:parent_frame"][-1][0], T)
    return edges


def frame_edges_at(recording: dict[str, Rows], time_ns: int) -> dict[str, tuple[str, np.ndarray]]:
    """Child frame → (parent frame, T_parent_child) as a viewer resolves them at ``time_ns``: every static
    ``Transform3D`` naming its frames, then for each child the latest temporal row at or before that time."""
    edges = static_edges(recording)
    for rows in recording.values():
        children = rows.temporal.get("Transform3D:child_frame")
        if not children:
            continue
        latest: dict[str, int] = {}
        for i, t in enumerate(rows.times):
            if t <= time_ns and children[i] is not None:
                latest[children[i][0]] = i
        for child, i in latest.items():
            t, q = (rows.temporal.get(f"Transform3D:{c}", [None] * (i + 1))[i] for c in ("translation", "quaternion"))
            edges[child] = (rows.temporal["Transform3D:parent_frame"][i][0], pose(t and t[0], q and q[0]))
    return edges


def pose_in(edges: dict[str, tuple[str, np.ndarray]], frame: str, fixed: str) -> np.ndarray:
    """T_fixed_frame composed along the edges."""
    T = np.eye(4)
    seen = set()
    while frame != fixed:
        if frame in seen or frame not in edges:
            raise KeyError(f"no path from {frame!r} to {fixed!r}")
        seen.add(frame)
        parent, T_parent_frame = edges[frame]
        T = T_parent_frame @ T
        frame = parent
    return T


def rows_in_order(path: str | Path, under: tuple[str, ...] = ("/",)) -> dict[str, list[tuple[int, dict[str, Any]]]]:
    """Entity (those under ``under``) → its rows as Rerun orders them (by time, then row id: rows at one time in the
    order they were logged, whichever chunk holds them), each {component: value}; static rows at time -1."""
    reader = RrdReader(path)
    out: dict[str, list[tuple[int, bytes, dict[str, Any]]]] = {}
    for chunk in reader.stream(store=reader.recordings()[0]):
        if not chunk.entity_path.startswith(under):
            continue
        batch = chunk.to_record_batch()
        skip = {"time", "log_time", "log_tick"}
        columns = {f.name: batch.column(i).to_pylist() for i, f in enumerate(batch.schema) if f.name not in skip}
        names = batch.schema.names
        times = batch.column(names.index("time")).cast("int64").to_pylist() if "time" in names else [-1] * len(batch)
        ids = columns.pop("rerun.controls.RowId")
        for i in range(batch.num_rows):
            row = {k: v[i] for k, v in columns.items() if v[i] is not None}
            out.setdefault(chunk.entity_path, []).append((times[i], ids[i], row))
    return {e: [(t, row) for t, _, row in sorted(rows, key=lambda r: (r[0], r[1]))] for e, rows in out.items()}
