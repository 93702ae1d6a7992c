"""Cyclone DDS topic types for ROS 2 messages, built at run time from rosbags' message definitions.

Cyclone's Python binding keeps every sample as its serialized bytes and checks them against the topic type (it
normalises incoming CDR with the type's ops), so a reader needs the message's real structure — but the samples
are never turned into Python objects: :mod:`.dds` takes the bytes as they came off the wire. The structs are
``@final`` with the ROS 2 DDS names (``std_msgs::msg::dds_::Header_``), exactly what rmw implementations declare.
"""

from __future__ import annotations

from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys.store import Typestore

from r2d2_viz.sources.live.names import LiveError, dds_type


class RawSample:
    """A sample as it came off the wire (encapsulation header + CDR body); cyclonedds sets ``sample_info``."""

    __slots__ = ("data", "sample_info")

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.sample_info: Any = None


def _keep_bytes(cls: Any, data: bytes, has_header: bool = True, use_version_2: bool | None = None) -> RawSample:
    return RawSample(data)


class IdlTypes:
    """Builds (once per type) the cyclonedds ``IdlStruct`` of ROS 2 message types from a rosbags typestore."""

    def __init__(self, store: Typestore, idl: Any) -> None:
        self._store = store
        self._idl = idl
        types = idl.types
        self._base: dict[str, Any] = {
            "bool": bool,
            "byte": types.byte,
            "octet": types.byte,
            "char": types.uint8,
            "int8": types.int8,
            "uint8": types.uint8,
            "int16": types.int16,
            "uint16": types.uint16,
            "int32": types.int32,
            "uint32": types.uint32,
            "int64": types.int64,
            "uint64": types.uint64,
            "float32": types.float32,
            "float64": types.float64,
        }
        self._structs: dict[str, Any] = {}

    def struct(self, ros_type: str) -> Any:
        """The ``IdlStruct`` subclass for ``ros_type`` (``pkg/msg/T``); LiveError if rosbags does not know it."""
        found = self._structs.get(ros_type)
        if found is None:
            found = self._structs[ros_type] = self._make(ros_type)
        return found

    def raw_struct(self, ros_type: str) -> Any:
        """The same DDS type for a topic, but read raw: its ``deserialize`` (the classmethod ``DataReader.take``
        calls on each sample) keeps the bytes in a :class:`RawSample` — Cyclone still checks every sample
        against the real type, and no Python message is ever built."""
        raw = self._make(ros_type)
        raw.deserialize = classmethod(_keep_bytes)
        return raw

    def _make(self, ros_type: str) -> Any:
        if ros_type not in self._store.fielddefs:
            raise LiveError(f"message type {ros_type} is not known (rosbags' definitions of this ROS 2 distro)")
        fields = {name: self._field(desc) for name, desc in self._store.fielddefs[ros_type][1]}
        name = dds_type(ros_type)
        return self._idl.make_idl_struct(name.rsplit("::", 1)[-1], name, fields)

    def _field(self, desc: tuple[Any, Any]) -> Any:
        kind, rest = desc
        types = self._idl.types
        if kind == Nodetype.BASE:
            base, bound = rest
            if base in ("string", "wstring"):
                return types.bounded_str[bound] if bound else str
            if base not in self._base:
                raise LiveError(f"field type {base} is not supported")
            return self._base[base]
        if kind == Nodetype.NAME:
            return self.struct(rest)
        sub, size = rest
        if kind == Nodetype.ARRAY:
            return types.array[self._field(sub), size]
        return types.sequence[self._field(sub), size] if size else types.sequence[self._field(sub)]
