"""Foxglove's message paths, the common cases: ``/odom.twist.twist.linear.x``, ``/joint_states.effort[2]``,
``/panda_arm_controller/state.error.positions[0]`` — a topic, then fields by name and array items by index (from
0). The field part is the column name :mod:`r2d2_viz.msgs.generic.fields` gives the value. Checked against the topic's
definition before anything is read (:func:`check_field`). Pure: no rerun, rosbags' typestore passed in.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from r2d2_viz.msgs.typestore import MsgError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

_INDEX = r"\[(?:0|-?[1-9][0-9]*)\]"
_PART = re.compile(rf"([A-Za-z_][A-Za-z0-9_]*)((?:{_INDEX})*)")
_TOPIC = re.compile(r"/?(?:[A-Za-z_~][A-Za-z0-9_]*)(?:/[A-Za-z_][A-Za-z0-9_]*)*")


_FILTER = re.compile(
    r"\{\s*([A-Za-z_][A-Za-z0-9_]*(?:" + _INDEX + r")*(?:\.[A-Za-z_][A-Za-z0-9_]*(?:" + _INDEX + r")*)*)\s*"
    r"(==|!=|<=|>=|<|>)\s*(-?[0-9][0-9.eE+-]*|true|false|\"[^\"]*\"|'[^']*')\s*\}"
)
_OPS = {"==": "__eq__", "!=": "__ne__", "<": "__lt__", "<=": "__le__", ">": "__gt__", ">=": "__ge__"}


@dataclass(frozen=True)
class Filter:
    """``{field OP value}`` after the topic: only the messages whose ``field`` compares so are plotted."""

    field: str
    op: str
    value: float | str

    def mask(self, column: np.ndarray) -> np.ndarray:
        """Which rows of ``column`` (the field's values) pass."""
        if isinstance(self.value, str) != (column.dtype == object):
            return np.zeros(len(column), dtype=bool)  # text against a number: nothing passes (as in Foxglove)
        out: np.ndarray = np.asarray(getattr(column, _OPS[self.op])(self.value), dtype=bool)
        return out


@dataclass(frozen=True)
class MessagePath:
    text: str
    topic: str
    field: str
    """``twist.twist.linear.x``, ``effort[2]`` (the column's name)."""
    filters: tuple[Filter, ...] = ()


def parse_path(text: str, topics: set[str] | None = None) -> MessagePath:
    """``TOPIC.FIELD[.FIELD…]`` (``[N]`` after a field: its item N). ``topics``: the topics a path may name (the
    longest one before a ``.`` wins); ``MsgError`` when it is not such a path."""
    ends = [i for i in (text.find("."), text.find("{")) if i >= 0]
    if not text.startswith("/") or not ends:
        raise MsgError(f"{text}: not a message path (TOPIC.FIELD, e.g. /odom.twist.twist.linear.x)")
    topic = text[: min(ends)]
    if topics is not None:
        known = [t for t in topics if text.startswith(t + ".") or text.startswith(t + "{")]
        if known:
            topic = max(known, key=len)
    rest, filters = text[len(topic) :], []
    while rest.startswith("{"):
        found = _FILTER.match(rest)
        if found is None:
            raise MsgError(
                f"{text}: {rest[: rest.find('}') + 1]!r}: a filter is {{FIELD OP VALUE}} (OP: == != < <= > >=)"
            )
        value = found.group(3)
        number = value[0] not in "\"'"
        parsed = (value == "true") if value in ("true", "false") else float(value) if number else value[1:-1]
        filters.append(Filter(found.group(1), found.group(2), parsed))
        rest = rest[found.end() :]
    if not _TOPIC.fullmatch(topic):
        raise MsgError(f"{text}: {topic!r} is not a topic name")
    if not rest.startswith(".") or len(rest) == 1:
        raise MsgError(f"{text}: not a message path (TOPIC.FIELD, e.g. /odom.twist.twist.linear.x)")
    rest = rest[1:]
    whole = rest[:-3] if rest.endswith("[:]") else rest  # a slice of the last array: all its items
    if not all(_PART.fullmatch(p) for p in whole.split(".")):
        raise MsgError(f"{text}: {_form(whole)}")
    return MessagePath(text, topic, rest, tuple(filters))


def _form(rest: str) -> str:
    """Why the field part of a path is not read, naming the form."""
    if "$" in rest:
        return "variables ($name) are not read: give the value"
    if "[:]" in rest:
        return "a slice ([:]) is read at the end of a path only (/scan.ranges[:]), not of messages"
    if re.search(r"\[-?\d*:-?\d*\]", rest):
        return "a slice with bounds ([1:3]) is not read: all items ([:]), or one (name[0], name[-1] for the last)"
    if "{" in rest:
        return "a filter inside the path is not read: filter on the topic (/topic{field==value}.x)"
    if re.search(r"\[-?0\d+\]", rest):
        return "an index with a leading zero ([01]): write it as a number ([1])"
    return f"{rest!r}: fields by name, items by index (name[2], name[-1])"


def picks(names: frozenset[str]) -> dict[str, tuple[int, ...]]:
    """Array name → the indices the field names ``names`` take in it (``points[-1].positions[2]``: ``points`` → -1
    and ``points[-1].positions`` → 2)."""
    out: dict[str, set[int]] = {}
    for name in names:
        for m in re.finditer(r"\[(-?\d+)\]", name):
            out.setdefault(name[: m.start()], set()).add(int(m.group(1)))
    return {k: tuple(sorted(v)) for k, v in out.items()}


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


def check_field(store: Typestore, msgtype: str, field: str, *, text: bool = False) -> str | None:
    """Why ``field`` names no number (``text``: or text) in messages of ``msgtype`` (None: it may, an index past an
    array's end aside)."""
    if field.endswith("[:]"):  # every item of an array of numbers
        why = check_field(store, msgtype, field[:-3] + "[0]")
        fixed = check_field(store, msgtype, field[:-3])
        if why is not None or fixed is None or "is an array" not in fixed:
            return f"{field[:-3]} is not an array of numbers (a slice is read of those only)"
        return None
    name: Any = msgtype
    for part in field.split("."):
        match = _PART.fullmatch(part)
        if match is None or not isinstance(name, str) or name not in store.fielddefs:
            return f"{part} is not a field"
        fields = dict(store.fielddefs[name][1])
        if match.group(1) not in fields:
            return f"{msgtype} has no field {match.group(1)} there"
        kind, rest = fields[match.group(1)]  # type: Any, Any
        for index in re.findall(r"\[(-?\d+)\]", match.group(2)):
            if kind not in (3, 4):
                return f"{match.group(1)} is not an array"
            if kind == 3 and not -rest[1] <= int(index) < rest[1]:
                return f"{match.group(1)} has {rest[1]} items"
            kind, rest = rest[0]
        name = rest if kind == 2 else (rest[0] if kind == 1 else None)
        if kind in (3, 4):
            return f"{match.group(1)} is an array: give an index ({match.group(1)}[0])"
    if name in store.fielddefs:
        return f"{field} is a message, not a number"
    if name in ("string", "wstring") and not text:
        return f"{field} is text, not a number"
    return None
