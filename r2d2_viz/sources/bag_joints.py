"""``/joint_states`` (``sensor_msgs/msg/JointState``) decoded into chunks of samples, from a bag or a live graph, and
a bag's latest ``/robot_description`` (``/tf`` and ``/tf_static``: :mod:`r2d2_viz.sources.bag_tf`).

Messages are decoded in bulk: messages with the same joint names share a byte layout (:mod:`r2d2_viz.msgs.layouts`),
so each is checked against its layout with one bytes comparison and all positions of a chunk become one numpy
array; anything else (big-endian, malformed) goes through rosbags' deserializer. Pure: no rerun import.

A message names some joints: its sample gives those, NaN elsewhere (the joint keeps its last value, as with
robot_state_publisher). Names that are not actuated joints of the robot are ignored, with one warning; a
message whose name and position lengths differ is skipped, and the skipped ones are counted in one warning.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from r2d2_viz.arrays import F64, I64
from r2d2_viz.errors import BagError
from r2d2_viz.msgs.layouts import STAMP, JointStateLayout, joint_state_layout
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.base import SampleChunk

JOINT_STATE = "sensor_msgs/msg/JointState"
STRING = "std_msgs/msg/String"
TimeSource = Literal["receive", "header"]
_STAMP = np.dtype([("sec", "<i4"), ("nsec", "<u4")])
MAX_LAYOUTS = 64
"""Byte layouts remembered (one per set of joint names); a publisher whose names change every message evicts."""
MAX_UNKNOWN = 1000
"""Unknown joint names remembered for the warning (a 10,000-name message must not grow it without end)."""


def stamps_ns(stamps: bytes) -> I64:
    """``builtin_interfaces/Time`` records (8 bytes each) to int64 nanoseconds."""
    s = np.frombuffer(stamps, dtype=_STAMP)
    ns: I64 = s["sec"].astype(np.int64) * 1_000_000_000 + s["nsec"].astype(np.int64)
    return ns


@dataclass
class _Group:
    """Messages of one layout within a chunk."""

    layout: JointStateLayout
    rows: list[int] = field(default_factory=list)
    values: list[bytes | memoryview] = field(default_factory=list)  # whole messages, all of one length


class JointStateDecoder:
    """JointState messages (CDR bytes) to :class:`SampleChunk` s of the robot's ``actuated`` joints, in bulk;
    ``deserialize(data, msgtype)`` (raising BagError or MsgError) decodes what no byte layout fits. Counts what it
    skips: :meth:`problems` says it (a bag's source and a live graph's share this)."""

    def __init__(
        self,
        actuated: Sequence[str],
        *,
        time: TimeSource = "receive",
        deserialize: Callable[[bytes | memoryview, str], Any],
    ) -> None:
        self.joints = tuple(actuated)
        self.time = time
        self._deserialize = deserialize
        self._column = {name: i for i, name in enumerate(self.joints)}
        self.skipped = self.undecodable = self.nonfinite = 0
        self.unknown: set[str] = set()
        self._layouts: list[JointStateLayout] = []

    def problems(self) -> list[str]:
        """One line per kind of message skipped or joint ignored so far."""
        out = []
        if self.unknown:
            names = ", ".join(sorted(self.unknown)[:10]) + (", ..." if len(self.unknown) > 10 else "")
            out.append(f"ignored joints that are not actuated joints of the robot: {names}")
        if self.skipped:
            out.append(f"skipped {self.skipped} messages whose name and position lengths differ")
        if self.undecodable:
            out.append(f"skipped {self.undecodable} messages that cannot be decoded")
        if self.nonfinite:
            out.append(f"{self.nonfinite} messages had NaN or infinite positions (those joints kept their last value)")
        return out

    def _layout_of(self, data: bytes | memoryview) -> JointStateLayout | None:
        for layout in self._layouts:
            if layout.matches(data):
                return layout
        try:
            layout = joint_state_layout(data)
        except ValueError:
            return None
        if len(self._layouts) >= MAX_LAYOUTS:  # names that change every message: memory stays bounded
            self._layouts.pop(0)
        self._layouts.append(layout)
        if len(self.unknown) < MAX_UNKNOWN:
            self.unknown.update(name for name in layout.names if name not in self._column)
        return layout

    def decode(self, messages: Sequence[tuple[int, bytes | memoryview]]) -> SampleChunk | None:
        """``(receive time ns, CDR bytes)`` pairs to one chunk (None: no message could be used)."""
        groups: dict[tuple[int, int], _Group] = {}  # (layout, message length) → its messages: one matrix
        times: list[int] = []
        singles: list[tuple[int, tuple[str, ...], F64, int]] = []  # messages rosbags had to decode
        group: _Group | None = None
        key, key_end, size = b"", 0, -1
        for receive_ns, data in messages:
            if len(data) == size and data[12:key_end] == key:  # the same layout as the last message
                assert group is not None
                group.rows.append(len(times))
                group.values.append(data)
                times.append(receive_ns)
                continue
            layout = self._layout_of(data)
            if layout is None:
                try:
                    names, positions, stamp_ns = self._generic(data)
                except (BagError, MsgError):
                    self.undecodable += 1
                    continue
                if len(names) != len(positions):
                    self.skipped += 1
                    continue
                singles.append((len(times), names, positions, stamp_ns))
                times.append(receive_ns)
                continue
            if layout.count != len(layout.names):
                self.skipped += 1
                continue
            group = groups.setdefault((id(layout), len(data)), _Group(layout))
            key, key_end, size = layout.key, 12 + len(layout.key), len(data)
            group.rows.append(len(times))
            group.values.append(data)
            times.append(receive_ns)
        if not times:
            return None
        seen = {name for g in groups.values() for name in g.layout.names} | {n for s in singles for n in s[1]}
        joints = tuple(j for j in self.joints if j in seen)
        column = {name: i for i, name in enumerate(joints)}
        positions = np.full((len(times), len(joints)), np.nan)
        header = np.zeros(len(times), dtype=np.int64)
        for (_, length), g in groups.items():
            rows = np.asarray(g.rows)
            raw = np.frombuffer(b"".join(g.values), dtype=np.uint8).reshape(len(rows), length)
            header[rows] = stamps_ns(raw[:, STAMP].tobytes())
            names = g.layout.names
            keep = [i for i, name in enumerate(names) if name in column]
            if keep:
                block = raw[:, g.layout.positions : g.layout.end].copy().view("<f8")[:, keep]
                bad = ~np.isfinite(block)
                if bad.any():
                    self.nonfinite += int(np.count_nonzero(bad.any(axis=1)))
                    block[bad] = np.nan
                positions[rows[:, None], [column[names[i]] for i in keep]] = block
        for row, names, values, stamp_ns in singles:
            header[row] = stamp_ns
            self.nonfinite += int(not np.isfinite(values).all())
            for name, value in zip(names, values, strict=True):
                if name in column:
                    positions[row, column[name]] = value if np.isfinite(value) else np.nan
                elif name not in self._column and len(self.unknown) < MAX_UNKNOWN:
                    self.unknown.add(name)
        times_ns: I64 = np.asarray(times, dtype=np.int64) if self.time == "receive" else header
        return SampleChunk(times_ns, joints, positions)

    def _generic(self, data: bytes | memoryview) -> tuple[tuple[str, ...], F64, int]:
        msg = self._deserialize(data, JOINT_STATE)
        stamp = msg.header.stamp
        return tuple(msg.name), np.asarray(msg.position, dtype=np.float64), int(stamp.sec) * 10**9 + int(stamp.nanosec)


def monotonic(chunk: SampleChunk, last_ns: int, moved: int) -> tuple[SampleChunk, int, int]:
    """Times made non-decreasing (header stamps of several publishers may interleave out of order)."""
    t = chunk.times_ns
    fixed = np.maximum.accumulate(np.concatenate([[last_ns], t]))[1:]
    changed = int(np.count_nonzero(fixed != t))
    if changed:
        chunk = SampleChunk(fixed, chunk.joints, chunk.positions, chunk.frames)
    return chunk, int(fixed[-1]), moved + changed


def read_robot_description(bag: Bag, topic: str = "/robot_description") -> str | None:
    """The latest ``std_msgs/msg/String`` on ``topic`` (the URDF robot_state_publisher published), or None."""
    if not bag.require_type(topic, STRING):
        return None
    found = bag.last(topic)
    if found is None:
        return None
    text = bag.deserialize(found[1], STRING).data
    return str(text)
