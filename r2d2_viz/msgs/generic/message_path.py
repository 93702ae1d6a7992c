"""Foxglove's message paths, the common cases: ``/odom.twist.twist.linear.x``, ``/joint_states.effort[2]``,
``/panda_arm_controller/state.error.positions[0]`` — a topic, then fields by name and array items by index (from
0). The field part is the column name :mod:`r2d2_viz.msgs.generic.fields` gives the value. Checked against the topic's
definition before anything is read (:func:`check_field`). Pure: no rerun, rosbags' typestore passed in.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from r2d2_viz.msgs.typestore import MsgError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")
_TOPIC = re.compile(r"/?(?:[A-Za-z_~][A-Za-z0-9_]*)(?:/[A-Za-z_][A-Za-z0-9_]*)*")


@dataclass(frozen=True)
class MessagePath:
    text: str
    topic: str
    field: str
    """``twist.twist.linear.x``, ``effort[2]`` (the column's name)."""


def parse_path(text: str, topics: set[str] | None = None) -> MessagePath:
    """``TOPIC.FIELD[.FIELD…]`` (``[N]`` after a field: its item N). ``topics``: the topics a path may name (the
    longest one before a ``.`` wins); ``MsgError`` when it is not such a path."""
    dot = text.find(".")
    if not text.startswith("/") or dot < 0:
        raise MsgError(f"{text}: not a message path (TOPIC.FIELD, e.g. /odom.twist.twist.linear.x)")
    topic, rest = text[:dot], text[dot + 1 :]
    if topics is not None:
        known = [t for t in topics if text.startswith(t + ".")]
        if known:
            topic = max(known, key=len)
            rest = text[len(topic) + 1 :]
    if not _TOPIC.fullmatch(topic):
        raise MsgError(f"{text}: {topic!r} is not a topic name")
    parts = rest.split(".")
    if not all(_PART.fullmatch(p) for p in parts):
        raise MsgError(f"{text}: {rest!r}: fields by name, items by index (name[2]); slices and filters are not read")
    return MessagePath(text, topic, rest)


def field_names(store: Typestore, msgtype: str, *, depth: int = 6) -> list[str]:
    """The fields of ``msgtype`` as paths name them (arrays as ``name[i]``), for a message of what fields a topic
    has."""
    out: list[str] = []

    def walk(name: str, prefix: str, level: int) -> None:
        for field, desc in store.fielddefs[name][1]:
            path = prefix + field
            kind, rest = desc[0], desc[1]  # type: Any, Any
            if kind in (3, 4):
                path += "[i]"
                desc = rest[0]
                kind, rest = desc
            if kind == 2 and level < depth:
                walk(rest, path + ".", level + 1)
            else:
                out.append(path)

    walk(msgtype, "", 0)
    return out


def check_field(store: Typestore, msgtype: str, field: str) -> str | None:
    """Why ``field`` names no number in messages of ``msgtype`` (None: it may, an index past an array's end aside)."""
    name: Any = msgtype
    for part in field.split("."):
        match = _PART.fullmatch(part)
        if match is None or not isinstance(name, str) or name not in store.fielddefs:
            return f"{part} is not a field"
        fields = dict(store.fielddefs[name][1])
        if match.group(1) not in fields:
            return f"{msgtype} has no field {match.group(1)} there"
        kind, rest = fields[match.group(1)]  # type: Any, Any
        for index in re.findall(r"\[(\d+)\]", match.group(2)):
            if kind not in (3, 4):
                return f"{match.group(1)} is not an array"
            if kind == 3 and int(index) >= rest[1]:
                return f"{match.group(1)} has {rest[1]} items"
            kind, rest = rest[0]
        name = rest if kind == 2 else (rest[0] if kind == 1 else None)
        if kind in (3, 4):
            return f"{match.group(1)} is an array: give an index ({match.group(1)}[0])"
    if name in store.fielddefs:
        return f"{field} is a message, not a number"
    if name in ("string", "wstring"):
        return f"{field} is text, not a number"
    return None
