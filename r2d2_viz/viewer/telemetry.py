"""Log what is not drawn in 3D (:data:`r2d2_viz.msgs.shapes.Plain`): log lines as ``TextLog``, diagnostic statuses
as ``StateChange`` (one entity per status below the topic's, its key/values as fields), numbers as ``Scalars``
(named series), fixes as ``GeoPoints``. A :class:`PlainBook` per topic remembers what was said already: the series'
names and a state's colours are logged once, and each key/value field keeps the kind it was first logged as (Rerun
fixes a component's type at its first row)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import rerun as rr

from r2d2_viz.msgs import shapes

STATE_COLORS = {"OK": 0x2E7D32FF, "WARN": 0xF9A825FF, "ERROR": 0xC62828FF, "STALE": 0x757575FF}
"""rqt_robot_monitor's colours: green, yellow, red, grey."""
MAX_STATES = 64
"""A status's distinct states (level and message) given their level's colour; past this, the viewer's palette."""


@dataclass
class PlainBook:
    """What one topic's plain entities were given so far."""

    numeric: dict[tuple[str, str], bool] = field(default_factory=dict)
    """(entity, key) → whether the field is a number (its first value parsed as one)."""
    styled: set[str] = field(default_factory=set)
    """Entities whose series names are logged."""
    states: dict[str, list[str]] = field(default_factory=dict)
    """Status entity → its states so far (each given its level's colour)."""


def status_entity(entity_path: str, status: shapes.Status) -> str:
    """``<topic>/<part>/…``, each part of the status name escaped."""
    return "/".join([entity_path, *(rr.escape_entity_path_part(p) for p in status.parts)])


def state_of(status: shapes.Status) -> str:
    """What the state view shows: ``LEVEL: message`` (the level alone without a message)."""
    return f"{status.level}: {status.message}" if status.message else status.level


def _number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _fields(entity: str, status: shapes.Status, book: PlainBook) -> dict[str, object]:
    """The status's level, message, hardware id and key/values; a key first seen with a number stays a number
    (NaN when a later value is not one), one first seen with text stays text."""
    out: dict[str, object] = {"level": status.level, "message": status.message, "hardware_id": status.hardware_id}
    for key, text in status.values:
        if key in out:
            key = f"{key} (value)"
        value = _number(text)
        numeric = book.numeric.setdefault((entity, key), value is not None)
        out[key] = [(math.nan if value is None else value)] if numeric else [text]
    return out


def _statuses(rec: rr.RecordingStream, entity_path: str, item: shapes.Statuses, book: PlainBook) -> None:
    for status in item.items:
        entity, state = status_entity(entity_path, status), state_of(status)
        known = book.states.setdefault(entity, [])
        if state not in known and len(known) < MAX_STATES:
            known.append(state)
            colors = [STATE_COLORS.get(s.split(":", 1)[0], 0x1565C0FF) for s in known]
            rec.log(entity, rr.StateConfiguration(values=known, colors=np.array(colors, dtype=np.uint32)), static=True)
        rec.log(
            entity,
            rr.StateChange(state=state),
            rr.DynamicArchetype("DiagnosticStatus", components=_fields(entity, status, book)),  # type: ignore[arg-type]
        )


def log_plain(rec: rr.RecordingStream, entity_path: str, item: shapes.Plain, book: PlainBook) -> None:
    """Log one plain item of a message of the topic on ``entity_path`` (the time is set already)."""
    if isinstance(item, shapes.LogLine):
        rec.log(entity_path, rr.TextLog(item.text, level=item.level or None))
    elif isinstance(item, shapes.Statuses):
        _statuses(rec, entity_path, item, book)
    elif isinstance(item, shapes.Series):
        entity = f"{entity_path}/{item.name}" if item.name else entity_path
        if entity not in book.styled:
            book.styled.add(entity)
            rec.log(entity, rr.SeriesLines(names=list(item.labels)), static=True)
        rec.log(entity, rr.Scalars(item.values))
    else:
        rec.log(entity_path, rr.GeoPoints(lat_lon=[[item.latitude, item.longitude]], radii=rr.Radius.ui_points(6.0)))
