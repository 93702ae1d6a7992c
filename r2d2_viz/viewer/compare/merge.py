"""One run's recording as a part of a ``--compare`` recording: each chunk moved under ``/runs/<name>``, its times
shifted to the shared timeline (a duration since the run's alignment point), its TF frames renamed
``<name>/<frame>`` (each run keeps its own tree), a ghost's colours tinted and made translucent, and every plotted
series named ``NAME (run)``.

Chunks are rewritten as Arrow columns (Rerun's :class:`rerun.chunk.Chunk` ↔ ``RecordBatch``); what the summary
needs (frames, plotted series) is read on the same pass (:class:`RunFacts`)."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import rerun as rr
from rerun.chunk import Chunk, RrdReader

from r2d2_viz.arrays import F64
from r2d2_viz.viewer.entities import TIMELINE

RUNS = "/runs"
PROPERTIES = "/__properties"
FRAME_ID = b"rerun.components.TransformFrameId"
COLOR = b"rerun.components.Color"
ALBEDO = b"rerun.components.AlbedoFactor"
NAMES = {"SeriesLines:names", "SeriesPoints:names"}
SERIES = ("/plot/", "/joints/")
"""Entities whose scalars are plotted series (``--plot``'s, the joint states')."""
GHOST_ALPHA = 0.4
"""A ghost's opacity."""
MESHES = {"Mesh3D": "Mesh3D:vertex_positions", "Asset3D": "Asset3D:blob"}


@dataclass(frozen=True)
class RunStyle:
    """How one run is placed: its name, what is added to its times (ns), and its tint (RGBA; None: drawn as is)."""

    name: str
    shift_ns: int
    tint: tuple[int, int, int, int] | None = None

    @property
    def root(self) -> str:
        return f"{RUNS}/{self.name}"

    def frame(self, frame: str) -> str:
        """The run's frame in the shared scene (Rerun's entity frames, ``tf#/…``, move with their entity)."""
        return frame if frame.startswith("tf#") else f"{self.name}/{frame}"


@dataclass
class Series:
    """A plotted series of one run: its times on the run's own clock (ns) and values."""

    times: list[int] = field(default_factory=list)
    values: list[float] = field(default_factory=list)

    def arrays(self) -> tuple[np.ndarray, F64]:
        order = np.argsort(np.asarray(self.times, np.int64), kind="stable")
        return np.asarray(self.times, np.int64)[order], np.asarray(self.values, np.float64)[order]


@dataclass
class RunFacts:
    """What a run's recording says for the summary: its TF frames, its time span and its plotted series by name."""

    frames: set[str] = field(default_factory=set)
    first_ns: int | None = None
    last_ns: int | None = None
    series: dict[str, Series] = field(default_factory=lambda: defaultdict(Series))
    names: dict[str, list[str]] = field(default_factory=dict)
    """A series entity → the names of its scalars (``SeriesLines:names``)."""
    entities: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    """Entity → its timed rows (what an .rrd run counts instead of a bag's messages)."""
    firsts: dict[str, int] = field(default_factory=dict)
    """Entity → its first time (an .rrd run's ``--align`` point)."""

    def read(self, chunk: Chunk, batch: pa.RecordBatch) -> None:
        names = batch.schema.names
        for column in ("Transform3D:child_frame", "Transform3D:parent_frame"):
            if column in names:
                self.frames.update(v for v in pc.list_flatten(batch.column(column)).to_pylist() if v is not None)
        path = chunk.entity_path
        if chunk.is_static:
            for column in NAMES & set(names):
                self.names[path] = [str(n) for n in pc.list_flatten(batch.column(column)).to_pylist()]
            return
        if TIMELINE not in names:
            return
        times = batch.column(TIMELINE).cast(pa.int64()).to_numpy()
        self.entities[path] += len(times)
        if len(times):
            low, high = int(times.min()), int(times.max())
            self.first_ns = low if self.first_ns is None else min(self.first_ns, low)
            self.last_ns = high if self.last_ns is None else max(self.last_ns, high)
            self.firsts[path] = min(self.firsts.get(path, low), low)
        if path.startswith(SERIES) and not path.endswith("/limits") and "Scalars:scalars" in names:
            for row, values in zip(times.tolist(), batch.column("Scalars:scalars").to_pylist(), strict=True):
                for k, value in enumerate(values or ()):
                    if value is not None:
                        mine = self.series[f"{path}#{k}"]
                        mine.times.append(row)
                        mine.values.append(float(value))

    def named_series(self) -> dict[str, tuple[np.ndarray, F64]]:
        """Each series by its name (``/joint_states.position[0]``, a joint's name), times sorted."""
        out = {}
        for key, series in self.series.items():
            path, _, k = key.rpartition("#")
            names = self.names.get(path, [])
            name = names[int(k)] if int(k) < len(names) else path
            out[name] = series.arrays()
        return out


def _tinted(colors: pa.Array, tint: tuple[int, int, int, int], keep: float) -> pa.Array:
    """Packed RGBA colours blended toward ``tint`` (``keep``: how much of the colour stays), alpha scaled by the
    tint's alpha."""
    values = pc.list_flatten(colors).to_numpy(zero_copy_only=False).astype(np.uint32)
    rgb = np.stack([(values >> s) & 0xFF for s in (24, 16, 8)], axis=-1).astype(np.float64)
    rgb = keep * rgb + (1 - keep) * np.asarray(tint[:3], np.float64)
    alpha = ((values & 0xFF) * (tint[3] / 255.0)).round()
    r, g, b = (rgb.round().astype(np.uint32)[:, i] for i in range(3))
    packed = (r << 24) | (g << 16) | (b << 8) | alpha.astype(np.uint32)
    return _relist(colors, pa.array(packed, pa.uint32()))


def _relist(column: pa.Array, values: pa.Array) -> pa.Array:
    """``values`` (one per item of the list column ``column``, flattened) as a list column of ``column``'s shape,
    its empty rows (a component a row does not have) kept empty."""
    offsets = pc.subtract(column.offsets, column.offsets[0])
    return pa.ListArray.from_arrays(offsets, values, mask=column.is_null() if column.null_count else None)


def _one_each(n: int, value: int) -> pa.Array:
    return pa.ListArray.from_arrays(pa.array(np.arange(n + 1, dtype=np.int32)), pa.array([value] * n, pa.uint32()))


def rewrite(chunk: Chunk, style: RunStyle, facts: RunFacts | None = None) -> Chunk | None:
    """``chunk`` of a run's recording as a part of the comparison (None: nothing of it goes there: the recording's
    properties, rows on other timelines only)."""
    if chunk.entity_path.startswith(PROPERTIES):
        return None
    batch = chunk.to_record_batch()
    if facts is not None:
        facts.read(chunk, batch)
    if not chunk.is_static and TIMELINE not in batch.schema.names:
        return None
    fields: list[pa.Field] = []
    columns: list[pa.Array] = []
    archetypes: set[str] = set()
    for f, column in zip(batch.schema, batch.columns, strict=True):
        meta = f.metadata or {}
        kind = meta.get(b"rerun:kind")
        if kind == b"control":
            continue  # fresh row ids: the same recording given twice is two runs
        if kind == b"index":
            if f.name != TIMELINE:
                continue
            shifted = pc.add(column.cast(pa.int64()), pa.scalar(style.shift_ns, pa.int64()))
            column, f = shifted.cast(pa.duration("ns")), pa.field(f.name, pa.duration("ns"), metadata=meta)
        elif meta.get(b"rerun:component_type") == FRAME_ID:
            flat = [None if v is None else style.frame(v) for v in pc.list_flatten(column).to_pylist()]
            column = _relist(column, pa.array(flat, pa.string()))
        elif f.name in NAMES:
            flat = [None if v is None else f"{v} ({style.name})" for v in pc.list_flatten(column).to_pylist()]
            column = _relist(column, pa.array(flat, pa.string()))
        elif meta.get(b"rerun:component_type") in (COLOR, ALBEDO) and style.tint is not None:
            series = f.name.startswith("Series")
            column = _tinted(column, style.tint if not series else (*style.tint[:3], 255), 0.5 if series else 0.15)
        archetypes.add(f.name.partition(":")[0])
        fields.append(f)
        columns.append(column)
    if style.tint is not None:  # a ghost's mesh without a colour of its own: the tint as its albedo factor
        for archetype, shape in MESHES.items():
            albedo = f"{archetype}:albedo_factor"
            if shape in batch.schema.names and albedo not in batch.schema.names:
                tint = int.from_bytes(bytes(style.tint), "big")
                fields.append(pa.field(albedo, pa.list_(pa.uint32()), metadata=_albedo_meta(archetype)))
                columns.append(_one_each(batch.num_rows, tint))
    meta = {k: v for k, v in (batch.schema.metadata or {}).items() if k != b"rerun:id"}
    meta[b"rerun:entity_path"] = (style.root + chunk.entity_path).encode()
    out = pa.RecordBatch.from_arrays(columns, schema=pa.schema(fields, metadata=meta))
    made = Chunk.from_record_batch(out, index=None if chunk.is_static else TIMELINE)
    return made[0] if made else None


def _albedo_meta(archetype: str) -> dict[bytes, bytes]:
    return {
        b"rerun:archetype": f"rerun.archetypes.{archetype}".encode(),
        b"rerun:component": f"{archetype}:albedo_factor".encode(),
        b"rerun:component_type": b"rerun.components.AlbedoFactor",
        b"rerun:kind": b"data",
    }


def recording_chunks(path: Path) -> Iterator[Chunk]:
    """The chunks of the (first) recording in an ``.rrd`` file."""
    reader = RrdReader(path)
    yield from reader.stream(store=reader.recordings()[0])


def rewritten(path: Path, style: RunStyle, facts: RunFacts) -> Iterator[Chunk]:
    """Every chunk of the run's ``.rrd`` rewritten by :func:`rewrite` (``facts`` gathered on the way)."""
    for chunk in recording_chunks(path):
        out = rewrite(chunk, style, facts)
        if out is not None:
            yield out


def send_run(rec: rr.RecordingStream, path: Path, style: RunStyle) -> None:
    """The run's ``.rrd`` into ``rec``, rewritten by :func:`rewrite`, chunk by chunk."""
    rr.send_chunks(rewritten(path, style, RunFacts()), recording=rec)


@dataclass
class RunView:
    """What a run's own blueprint says of its 3D view: the fixed frame (None: it has none), the eye
    (``position``, ``look_target``, ``eye_up``) and the entities it hides (collision shapes, unticked displays)."""

    frame: str | None = None
    eye: dict[str, list[float]] = field(default_factory=dict)
    hidden: list[str] = field(default_factory=list)


OVERRIDES = "/ViewContents/overrides/"


def blueprint_view(path: Path) -> RunView:
    """The :class:`RunView` of the (first) blueprint an ``.rrd`` holds (an empty one: it holds none)."""
    reader = RrdReader(path)
    stores = reader.blueprints()
    view = RunView()
    if not stores:
        return view
    for chunk in reader.stream(store=stores[0]):
        batch = chunk.to_record_batch()
        for name in batch.schema.names:
            if not name.startswith(("SpatialInformation:", "EyeControls3D:", "EntityBehavior:visible")):
                continue
            values = batch.column(name).to_pylist()
            if not values or not values[-1]:
                continue
            if name == "SpatialInformation:target_frame":
                view.frame = str(values[-1][0])
            elif name.startswith("EyeControls3D:"):
                view.eye[name.partition(":")[2]] = list(values[-1][0]) if isinstance(values[-1][0], list) else []
            elif values[-1] == [False] and OVERRIDES in chunk.entity_path:  # Rerun's .../<entity>/visualizers
                entity = chunk.entity_path.partition(OVERRIDES)[2].removesuffix("/visualizers")
                view.hidden.append("/" + entity)
    return view
