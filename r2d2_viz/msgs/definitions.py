"""Messages decoded with the definitions their bag carries: a topic whose definition (a ROS 1 connection header's
``ros1msg``, an MCAP schema's ``ros2msg`` or ``ros2idl``) lays a type out as Humble does passes through untouched;
one that differs (Noetic's or Foxy's ``Marker`` without the texture fields Humble added) is converted message by
message to Humble's layout — fields matched by name, missing ones given their defaults, extra ones dropped — so
that every decoder keeps reading Humble layouts. Also ROS 1 messages to CDR, with the bag's own definitions.

Pure: no rerun import; rosbags is imported on first use.
"""

from __future__ import annotations

import dataclasses
import functools
import re
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from r2d2_viz.errors import one_line
from r2d2_viz.msgs.generic.known_layouts import known_humble
from r2d2_viz.msgs.typestore import MAX_MESSAGE_BYTES, MsgError, typestore

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

Convert = Callable[[bytes | memoryview], memoryview]
"""One message's bytes in, its CDR bytes in Humble's layout out; fails only with ``MsgError``."""

MAX_DEFINITION_CHARS = 1 << 20
ENCODINGS = ("ros1msg", "ros2msg", "ros2idl")
_ROSLIB_HEADER = re.compile(r"\broslib/Header\b")
_IDL_DELIMITER = re.compile(r"^={80}\r?\nIDL: *\S*[ \t]*\r?\n", re.MULTILINE)
"""What precedes each IDL file of a ``ros2idl`` schema (rosbag2's docs/message_definition_encoding.md)."""
_PREPROCESSOR = re.compile(r"^[ \t]*#[^\n]*", re.MULTILINE)
"""``#include`` and ``#pragma`` lines: the files included are in the schema already (rosbags' parser takes none)."""
_ONE_BYTE = {"bool", "byte", "char", "int8", "uint8", "octet"}
"""One-byte types: the same on the wire (ROS 1's ``byte`` is ``int8``, ROS 2's is ``octet``)."""


def _unusable(msgtype: str, why: str) -> MsgError:
    return MsgError(f"{msgtype}: its message definition cannot be used: {why}")


@functools.cache
def own_store(msgtype: str, definition: str, encoding: str) -> Typestore:
    """A typestore of the types ``definition`` (in ``encoding``) gives for ``msgtype`` and its fields' types; types
    it names without defining come from Humble. ROS 1 definitions get ROS 2's ``std_msgs/msg/Header`` (rosbags'
    ROS 1 → CDR conversion drops ``seq``), also for pre-2010 ``roslib/Header``. A ``ros2idl`` schema is parsed one
    IDL file at a time, without its preprocessor lines. Raises ``MsgError``."""
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

    if encoding not in ENCODINGS:
        raise _unusable(msgtype, f"unknown encoding {encoding!r}")
    if len(definition) > MAX_DEFINITION_CHARS:
        raise _unusable(msgtype, f"{len(definition)} characters")
    try:
        if encoding == "ros2idl":
            typs = {}
            for idl in _IDL_DELIMITER.split(definition):  # one IDL file each (any order), or one without delimiter
                if text := _PREPROCESSOR.sub("", idl).strip():
                    typs.update(get_types_from_idl(text))
        else:
            text = _ROSLIB_HEADER.sub("std_msgs/Header", definition) if encoding == "ros1msg" else definition
            typs = get_types_from_msg(text, msgtype)
        if encoding == "ros1msg":
            typs.pop("std_msgs/msg/Header", None)
        store = get_typestore(Stores.EMPTY)
        store.register(typs)
        _fill_from_humble(store, msgtype)
    except MsgError:
        raise
    except Exception as exc:  # the parsers raise their own errors, KeyError, RecursionError ...
        raise _unusable(msgtype, one_line(exc)) from None
    return store


def _names(desc: Any) -> list[str]:
    """The message types a field description refers to."""
    kind, rest = desc
    if kind == 2:  # NAME
        return [rest]
    if kind in (3, 4):  # ARRAY, SEQUENCE
        return _names(rest[0])
    return []


def _fill_from_humble(store: Typestore, msgtype: str) -> None:
    """Registers in ``store`` Humble's definition of every type reachable from ``msgtype`` that it lacks."""
    humble, todo, seen = typestore(), [msgtype], set()
    missing: dict[str, Any] = {}
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        if name in store.fielddefs:
            fields = store.fielddefs[name][1]
        elif name in humble.fielddefs:
            missing[name] = humble.fielddefs[name]
            fields = humble.fielddefs[name][1]
        else:
            raise _unusable(msgtype, f"it uses {name}, which it does not define")
        for _, desc in fields:
            todo += _names(desc)
    if missing:
        store.register(missing)


def _wire(desc: Any) -> Any:
    kind, rest = desc
    if kind == 1:
        return (1, "1" if rest[0] in _ONE_BYTE else rest[0], rest[1])
    return desc


def same_layout(own: Typestore, msgtype: str, humble: Typestore, humble_type: str) -> bool:
    """Whether ``msgtype`` in ``own`` has the wire layout of ``humble_type`` in ``humble`` (field names aside, as
    ``rosbags-convert`` decides; the decoders read Humble's fields by position)."""
    seen: set[tuple[str, str]] = set()

    def same(a: str, b: str) -> bool:
        if (a, b) in seen:
            return True
        seen.add((a, b))
        fa, fb = own.fielddefs[a][1], humble.fielddefs[b][1]
        return len(fa) == len(fb) and all(same_desc(da, db) for (_, da), (_, db) in zip(fa, fb, strict=True))

    def same_desc(da: Any, db: Any) -> bool:
        if da[0] != db[0]:
            return False
        if da[0] == 1:
            return bool(_wire(da) == _wire(db))
        if da[0] == 2:
            return same(da[1], db[1])
        return bool(da[1][1] == db[1][1]) and same_desc(da[1][0], db[1][0])

    return same(msgtype, humble_type)


# --- migration: a message of the bag's layout → Humble's -----------------------------------------------------------


def _dtype(base: str) -> np.dtype[Any]:
    return np.dtype({"char": "uint8", "byte": "uint8", "octet": "uint8", "bool": "bool"}.get(base, base))


def _default(store: Typestore, desc: Any) -> Any:
    kind, rest = desc
    if kind == 1:
        return "" if rest[0] in ("string", "wstring") else (False if rest[0] == "bool" else 0)
    if kind == 2:
        return store.types[rest](*(_default(store, d) for _, d in store.fielddefs[rest][1]))
    sub, size = rest
    size = size if kind == 3 else 0
    if sub[0] == 1 and sub[1][0] not in ("string", "wstring"):
        return np.zeros(size, dtype=_dtype(sub[1][0]))
    return [_default(store, sub) for _ in range(size)]


def _migrate_value(own: Typestore, humble: Typestore, value: Any, src: Any, dst: Any) -> Any:
    if src[0] != dst[0] and not ({src[0], dst[0]} <= {3, 4}):
        return _default(humble, dst)
    if dst[0] == 1:
        is_str = dst[1][0] in ("string", "wstring")
        if is_str != (src[1][0] in ("string", "wstring")):
            return _default(humble, dst)
        if is_str:
            return value
        return bool(value) if dst[1][0] == "bool" else (float(value) if "float" in dst[1][0] else int(value))
    if dst[0] == 2:
        return _migrate(own, humble, value, src[1], dst[1])
    (ssub, _), (dsub, size) = src[1], dst[1]
    if ssub[0] != dsub[0] or (dsub[0] == 1 and (ssub[1][0] == "string") != (dsub[1][0] == "string")):
        return _default(humble, dst)
    if dsub[0] == 1 and dsub[1][0] not in ("string", "wstring"):
        out = np.asarray(value).astype(_dtype(dsub[1][0]))
        if dst[0] == 3 and len(out) != size:
            out = np.resize(out, size) if len(out) else np.zeros(size, dtype=out.dtype)
            out[min(len(value), size) :] = 0
        return out
    items = [_migrate_value(own, humble, v, ssub, dsub) for v in value]
    if dst[0] == 3 and len(items) != size:
        items = (items + [_default(humble, dsub) for _ in range(size)])[:size]
    return items


def _migrate(own: Typestore, humble: Typestore, msg: Any, src_type: str, dst_type: str) -> Any:
    """``msg`` (of ``src_type`` in ``own``) as ``dst_type`` of ``humble``: fields matched by name (case aside)."""
    own_fields = own.fielddefs[src_type][1]
    attributes = [f.name for f in dataclasses.fields(msg)][: len(own_fields)]  # in order; then ``__msgtype__``
    src = {name.lower(): (desc, getattr(msg, a)) for (name, desc), a in zip(own_fields, attributes, strict=True)}
    values = []
    for name, desc in humble.fielddefs[dst_type][1]:
        have = src.get(name.lower())
        values.append(_default(humble, desc) if have is None else _migrate_value(own, humble, have[1], have[0], desc))
    return humble.types[dst_type](*values)


def _converter(own: Typestore, msgtype: str, humble: Typestore) -> Convert:
    def convert(data: bytes | memoryview) -> memoryview:
        if len(data) > MAX_MESSAGE_BYTES:
            raise MsgError(f"{msgtype}: message of {len(data)} bytes is too big")
        try:
            msg = own.deserialize_cdr(data, msgtype)
            return humble.serialize_cdr(_migrate(own, humble, msg, msgtype, msgtype), msgtype)
        except Exception as exc:  # rosbags raises struct.error, IndexError, ValueError ...
            raise MsgError(f"{msgtype}: cannot convert to Humble's layout: {one_line(exc)}") from None

    return convert


def to_humble(msgtype: str, definition: str, encoding: str) -> Convert | None:
    """How the messages of a topic of ``msgtype`` whose bag gives ``definition`` (``encoding``: ``ros1msg``,
    ``ros2msg``, ``ros2idl``; "" with none) become decodable as Humble's: None when their CDR bytes already are
    (the same layout, no definition, or a type the app does not decode), else a function converting each message's
    CDR bytes. Raises ``MsgError`` when the definition cannot be used (the answer, or the error, is worked out once
    per definition)."""
    convert, error = _to_humble(msgtype, definition, encoding)
    if error is not None:
        raise MsgError(str(error))
    return convert


@functools.cache
def _to_humble(msgtype: str, definition: str, encoding: str) -> tuple[Convert | None, MsgError | None]:
    if known_humble(msgtype, encoding, definition):  # rosbags' own definitions: no typestore needed
        return None, None
    humble = typestore()
    if not definition or msgtype not in humble.fielddefs:
        return None, None
    try:
        own = own_store(msgtype, definition, encoding)
    except MsgError as exc:
        return None, exc
    if same_layout(own, msgtype, humble, msgtype):
        return None, None
    return _converter(own, msgtype, humble), None


@functools.cache
def from_ros1(msgtype: str, definition: str) -> Convert:
    """ROS 1 serialised messages of ``msgtype`` (``pkg/msg/Type``) to CDR, laid out as ``definition`` (its ROS 1
    connection header's ``message_definition``) says. Raises ``MsgError``; the function too."""
    own = own_store(msgtype, definition, "ros1msg")

    def convert(raw: bytes | memoryview) -> memoryview:
        try:
            return own.ros1_to_cdr(raw, msgtype)
        except Exception as exc:  # SerdeError, struct.error, IndexError ...
            raise MsgError(f"{msgtype}: cannot convert from ROS 1: {one_line(exc)}") from None

    return convert
