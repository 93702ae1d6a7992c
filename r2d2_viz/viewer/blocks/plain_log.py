"""What is not drawn in 3D (:data:`r2d2_viz.msgs.shapes.Plain`), logged on entities in no frame: log lines as
``TextLog``, diagnostic statuses as ``StateChange`` (one entity per status below the topic's, its key/values as
fields), numbers as ``Scalars`` (named series), fixes as ``GeoPoints``; a :class:`PlainBook` per topic remembers
what was said (series' names and a state's colours are logged once, a status's fields are exactly its own)."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.telemetry import status_fields
from r2d2_viz.viewer.blocks.recorder import Recorder

STATE_COLORS = {"OK": 0x2E7D32FF, "WARN": 0xF9A825FF, "ERROR": 0xC62828FF, "STALE": 0x757575FF}
"""rqt_robot_monitor's colours: green, yellow, red, grey."""
MAX_STATES = 64
"""A status's distinct states (level and message) given their level's colour; past this, the viewer's palette."""


@dataclass
class PlainBook:
    """What one topic's plain entities were given so far."""

    keys: dict[str, set[str]] = field(default_factory=dict)
    """Status entity → every field its statuses have had (what a status lacks is logged empty: cleared)."""
    lanes: dict[str, str] = field(default_factory=dict)
    """Status entity → the status name it shows (distinct names never share one)."""
    styled: set[str] = field(default_factory=set)
    """Entities whose series names are logged."""
    states: dict[str, list[str]] = field(default_factory=dict)
    """Status entity → its states so far (each given its level's colour)."""


def status_entity(entity_path: str, status: shapes.Status) -> str:
    """``<topic>/<part>/…`` (the parts are safe already; escaped all the same)."""
    return "/".join([entity_path, *(rr.escape_entity_path_part(p) for p in status.parts)])


def state_of(status: shapes.Status) -> str:
    """What the state view shows: ``LEVEL: message`` (the level alone without a message)."""
    return f"{status.level}: {status.message}" if status.message else status.level


def _typed(fields: dict[str, object]) -> dict[str, object]:
    """Empty (cleared) fields as typed Arrow arrays: Rerun drops an empty one it cannot type."""
    return {k: pa.array(v) if isinstance(v, np.ndarray) and not len(v) else v for k, v in fields.items()}


class _Built:
    """An archetype's component batches, built once (``rr.AsComponents``)."""

    def __init__(self, batches: list[rr.DescribedComponentBatch]) -> None:
        self.batches = batches

    def as_component_batches(self) -> list[rr.DescribedComponentBatch]:
        return self.batches


@lru_cache(maxsize=1024)
def _state_change(state: str) -> _Built:
    """``rr.StateChange(state=state)``, built once per state: its converter cost ~0.1 ms a status (issue 46: 480
    statuses of the console bag's 120 diagnostics, 10 % of its display logging)."""
    return _Built(rr.StateChange(state=state).as_component_batches())


def _statuses(rec: Recorder, entity_path: str, item: shapes.Statuses, book: PlainBook) -> None:
    for status in item.items:
        entity, state = status_entity(entity_path, status), state_of(status)
        while book.lanes.setdefault(entity, status.name) != status.name:  # another name made the same path
            entity += "_"
        known = book.states.setdefault(entity, [])
        if state not in known and len(known) < MAX_STATES:
            known.append(state)
            colors = [STATE_COLORS.get(s.split(":", 1)[0], 0x1565C0FF) for s in known]
            rec.log(entity, rr.StateConfiguration(values=known, colors=np.array(colors, dtype=np.uint32)), static=True)
        rec.log(
            entity,
            _state_change(state),
            rr.DynamicArchetype(
                "DiagnosticStatus", components=_typed(status_fields(status, book.keys.setdefault(entity, set())))
            ),
        )


def log_plain(rec: Recorder, entity_path: str, item: shapes.Plain, book: PlainBook) -> None:
    """Log one plain item of a message of the topic on ``entity_path`` (the time is set already)."""
    if (
        not isinstance(item, shapes.Series)
        and not isinstance(rec, rr.RecordingStream)
        and rec.take(entity_path, item, "")
    ):
        return
    if isinstance(item, shapes.LogLine):
        rec.log(entity_path, rr.TextLog(item.text, level=item.level or None))
    elif isinstance(item, shapes.Statuses):
        _statuses(rec, entity_path, item, book)
    elif isinstance(item, shapes.Series):
        entity = f"{entity_path}/{item.name}" if item.name else entity_path
        if entity not in book.styled:
            book.styled.add(entity)
            rec.log(entity, rr.SeriesLines(names=list(item.labels)), static=True)
        if isinstance(rec, rr.RecordingStream) or not rec.take(entity, item, ""):
            rec.log(entity, rr.Scalars(item.values))
    else:
        rec.log(entity_path, rr.GeoPoints(lat_lon=[[item.latitude, item.longitude]], radii=rr.Radius.ui_points(6.0)))
