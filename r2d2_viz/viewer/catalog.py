"""Rerun's catalog: a folder of recordings served as one dataset, and what the fleet summary reads from it.

The server is the open-source one in rerun-sdk (``rerun.server.Server``, the same as ``rerun server -d
NAME=DIR``); the queries go through its client (``rerun.catalog``, DataFusion dataframes; ``rerun-sdk[catalog]``).
The catalog keys segments by recording id and skips symlinked ``.rrd`` files. Only plain Arrow and numpy leave
this module: the arithmetic of the summary lives in :mod:`r2d2_viz.fleet.summary`.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import rerun as rr
from rerun.chunk import RrdReader

from r2d2_viz.errors import SinkError, UsageError

MARKER_PROPERTY = "r2d2_viz"
"""The recording property a fleet conversion writes: JSON of the bag's name, size, mtime and the app's version."""
TOPICS_PROPERTY = "bag_topics"
"""JSON ``{topic: [type, message count]}`` from the bag's index, written by the fleet conversion."""
INSTALL_CATALOG = "pip install 'r2d2-viz[catalog]'"
PROPERTY_CHUNKS = 16
"""How far into a recording its properties are looked for (a fleet recording's are its first chunks): checking
whether an output of gigabytes is up to date reads kilobytes."""


def recording_marker(path: Path) -> tuple[str, str | None] | None:
    """The recording id of an ``.rrd`` and its :data:`MARKER_PROPERTY` (None: not one); None: unreadable."""
    try:
        reader = RrdReader(path)
        stores = reader.recordings()
        if not stores:
            return None
        store = stores[0]
        marker = None
        for k, chunk in enumerate(reader.stream(store=store)):  # the properties come first: read no further
            if chunk.entity_path == f"/__properties/{MARKER_PROPERTY}":
                batch = chunk.to_record_batch()
                if "value" in batch.schema.names:
                    values = batch.column("value").to_pylist()
                    marker = values[-1][0] if values and values[-1] else marker
            elif k >= PROPERTY_CHUNKS or not chunk.entity_path.startswith("/__properties"):
                break
        return str(store.recording_id), marker
    except Exception:  # a torn or foreign file: not up to date, converted again
        return None


@contextmanager
def catalog_server(directory: Path, *, name: str, bind: str = "127.0.0.1", port: int = 0) -> Iterator[Any]:
    """Rerun's catalog server serving ``directory`` as the dataset ``name``; shut down on leaving."""
    try:
        server = rr.server.Server(host=bind, port=port, datasets={name: str(directory)})
    except ValueError as exc:
        raise UsageError(f"--dataset {directory}: {exc}") from None
    except Exception as exc:
        raise SinkError(f"--dataset {directory}: the catalog server did not start on {bind}:{port}: {exc}") from None
    try:
        yield server
    finally:
        server.shutdown()


def register_layout(server: Any, name: str, directory: Path) -> Path | None:
    """Give the dataset ``name`` the layout its recordings were converted with (the ``.rbl`` a fleet conversion
    writes beside each ``.rrd``; the first by name): the viewer opens every recording on it. The blueprint embedded
    in an ``.rrd`` does not travel with the catalog's segments. None: no layout there (or the server refused it)."""
    layouts = sorted(p for p in directory.glob("*.rbl") if p.with_suffix(".rrd").is_file())
    if not layouts:
        return None
    try:
        server.client().get_dataset(name).register_blueprint(layouts[0].resolve().as_uri())
    except Exception:  # an older server, a torn file: the viewer's own layout then
        return None
    return layouts[0]


def server_url(server: Any) -> str:
    return str(server.url())


@dataclass
class FleetData:
    """What the summary needs from the catalog, per segment (recording id)."""

    segments: pa.Table
    """``segment``, ``bag`` (the marker's name), ``topics`` (JSON), ``start_ns``, ``end_ns``, ``size_bytes``."""
    joints: dict[str, tuple[np.ndarray, np.ndarray, list[str]]] = field(default_factory=dict)
    """segment → (times ns (n,), joint values (n, joints), joint names)."""
    edges: dict[str, list[tuple[str, str, np.ndarray, np.ndarray, np.ndarray]]] = field(default_factory=dict)
    """segment → every /tf and /tf_static row: (parent, child, times ns (n,) — empty for static, xyz (n, 3),
    xyzw (n, 4)). Rotations only as quaternions (as the app writes them; a matrix or axis-angle reads as none)."""
    links: dict[str, set[str]] = field(default_factory=dict)
    """segment → the robot's links (the frames its /robot/** shapes are drawn in)."""


def read_fleet(server: Any, name: str) -> FleetData:
    """Query the dataset ``name``: the segment table and the joint plots through DataFusion dataframes; the
    transforms chunk by chunk through the segment stores (the dataframe view keeps one row per entity and time,
    and /tf has one row per edge: several at a time)."""
    try:
        client = server.client()
    except Exception as exc:  # datafusion missing: the client refuses to start
        raise UsageError(f"--summary needs the catalog client ({INSTALL_CATALOG}): {exc}") from None
    dataset = client.get_dataset(name)
    data = FleetData(segments=_segments(dataset))
    for segment in data.segments.column("segment").to_pylist():
        data.joints[segment] = _joints(dataset, segment)
        data.edges[segment], data.links[segment] = _transforms(dataset, segment)
    return data


def _segments(dataset: Any) -> pa.Table:
    table = dataset.segment_table().to_arrow_table()
    names = table.schema.names

    def texts(column: str) -> list[str | None]:
        if column not in names:
            return [None] * table.num_rows
        return [v[-1] if v else None for v in table.column(column).to_pylist()]

    def times(column: str) -> pa.Array:
        if column not in names:
            return pa.nulls(table.num_rows, pa.int64())
        return table.column(column).cast(pa.timestamp("ns")).cast(pa.int64())

    bags = [json.loads(m)["bag"] if m else None for m in texts(f"property:{MARKER_PROPERTY}:value")]
    return pa.table(
        {
            "segment": table.column("rerun_segment_id"),
            "bag": pa.array(bags, pa.string()),
            "topics": pa.array(texts(f"property:{TOPICS_PROPERTY}:value"), pa.string()),
            "start_ns": times("time:start"),
            "end_ns": times("time:end"),
            "size_bytes": table.column("rerun_size_bytes"),
        }
    )


JOINT_ENTITIES = ("/joints/limited", "/joints/continuous")


def _joints(dataset: Any, segment: str) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The joint plots' values (one row per sample; NaN where a plot has no row at that time)."""
    selection = dataset.filter_segments(segment).filter_contents(list(JOINT_ENTITIES))
    columns = [f"{e}:Scalars:scalars" for e in JOINT_ENTITIES]
    static = selection.reader(index=None).to_arrow_table()
    names: list[str] = []
    present = []
    for entity, column in zip(JOINT_ENTITIES, columns, strict=True):
        key = f"{entity}:SeriesLines:names"
        if key in static.schema.names and static.num_rows and static.column(key)[0].is_valid:
            names += static.column(key)[0].as_py()
            present.append((column, len(static.column(key)[0].as_py())))
    if not present:
        return np.zeros(0, np.int64), np.zeros((0, 0)), []
    table = selection.reader(index="time").to_arrow_table()
    times = table.column("time").cast(pa.int64()).to_numpy()
    blocks = []
    for column, width in present:
        rows = table.column(column).to_pylist() if column in table.schema.names else [None] * len(times)
        blocks.append(np.array([r if r is not None and len(r) == width else [np.nan] * width for r in rows]))
    order = np.argsort(times, kind="stable")
    return times[order], np.hstack(blocks).reshape(len(times), -1)[order], names


def _transforms(
    dataset: Any, segment: str
) -> tuple[list[tuple[str, str, np.ndarray, np.ndarray, np.ndarray]], set[str]]:
    store = dataset.segment_store(segment, include_assets=False)
    edges = []
    links: set[str] = set()
    for chunk in store.stream().filter(content=["/tf", "/tf_static/**", "/robot/**"]):
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if chunk.entity_path.startswith("/robot/"):
            if "CoordinateFrame:frame" in names:
                links.update(f for row in batch.column("CoordinateFrame:frame").to_pylist() if row for f in row)
            continue
        if "Transform3D:child_frame" not in names:
            continue
        children = batch.column("Transform3D:child_frame").to_pylist()
        parents = _column(batch, "Transform3D:parent_frame", None)
        xyz = _column(batch, "Transform3D:translation", [0.0, 0.0, 0.0])
        quat = _column(batch, "Transform3D:quaternion", [0.0, 0.0, 0.0, 1.0])
        times = batch.column("time").cast(pa.int64()).to_pylist() if "time" in names else [None] * batch.num_rows
        by_edge: dict[tuple[str, str], list[tuple[int | None, list[float], list[float]]]] = {}
        for p, c, t, v, q in zip(parents, children, times, xyz, quat, strict=True):
            for i in range(len(c or ())):  # one edge per row as the app logs them; several are read too
                if p and v and q:
                    k = min(i, len(p) - 1), min(i, len(v) - 1), min(i, len(q) - 1)
                    if p[k[0]] is not None:  # (no parent frame: the entity tree's, not a TF edge)
                        by_edge.setdefault((p[k[0]], c[i]), []).append((t, v[k[1]], q[k[2]]))
        for (parent, child), rows in by_edge.items():
            stamps = np.array([r[0] for r in rows if r[0] is not None], np.int64)
            edges.append(
                (parent, child, stamps, np.array([r[1] for r in rows], float), np.array([r[2] for r in rows], float))
            )
    return edges, links


def _column(batch: pa.RecordBatch, name: str, default: Any) -> list[Any]:
    """Each row's values; a transform without this part has its identity (what the app writes has them all)."""
    if name not in batch.schema.names:
        return [[default]] * batch.num_rows
    return [v if v else [default] for v in batch.column(name).to_pylist()]
