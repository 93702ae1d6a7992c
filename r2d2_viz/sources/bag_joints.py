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
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import F64, I64
from r2d2_viz.errors import BagError, listed
from r2d2_viz.msgs.layouts import STAMP, JointStateLayout, joint_state_layout
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.bags.storage import Block, block_of
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
        self.skipped = self.undecodable = self.nonfinite = self.nameless = 0
        self.unknown: set[str] = set()
        self._layouts: list[JointStateLayout] = []

    def problems(self) -> list[str]:
        """One line per kind of message skipped or joint ignored so far."""
        out = []
        if self.unknown:
            names = listed(sorted(self.unknown))
            out.append(f"ignored joints that are not actuated joints of the robot: {names}")
        if self.skipped:
            out.append(f"skipped {self.skipped} messages whose name and position lengths differ")
        if self.nameless:
            out.append(
                f"skipped {self.nameless} messages with an empty name list (nothing says which joints they move)"
            )
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
        return self.decode_block(block_of([(t, "", data) for t, data in messages], ("",)))

    def decode_block(self, block: Block) -> SampleChunk | None:
        """A block of JointState messages to one chunk, in bulk: messages of one length and layout (the same
        names) are one ``(n, length)`` byte matrix whose positions are one float64 view; rosbags decodes the rest.
        None: no message could be used."""
        n = len(block)
        if n == 0:
            return None
        buf = np.frombuffer(block.buffer, dtype=np.uint8)
        groups: list[tuple[JointStateLayout, I64, npt.NDArray[np.uint8]]] = []
        singles: list[tuple[int, tuple[str, ...], F64, int]] = []
        bad = np.zeros(n, dtype=bool)
        for length in np.unique(block.lengths):
            rows = np.flatnonzero(block.lengths == length)
            raw = _matrix(buf, block.starts[rows], int(length))
            left = np.arange(len(rows))
            while len(left):
                first = int(left[0])
                layout = self._layout_of(raw[first].tobytes()) if length >= 12 else None
                if layout is None:
                    row = int(rows[first])
                    single = self._single(block.data(row))
                    if single is None:
                        bad[row] = True
                    else:
                        singles.append((row, *single))
                    left = left[1:]
                    continue
                key_end = 12 + len(layout.key)
                keys = raw[:, 12:key_end] if len(left) == len(raw) else raw[left, 12:key_end]  # first pass: no gather
                same = np.all(keys == raw[first, 12:key_end], axis=1)
                if not layout.names:  # ROS 1 publishers that send positions only: nothing says which joint
                    bad[rows[left[same]]] = True
                    self.nameless += int(np.count_nonzero(same))
                elif layout.count != len(layout.names):  # name and position lengths differ: all of them skipped
                    bad[rows[left[same]]] = True
                    self.skipped += int(np.count_nonzero(same))
                else:
                    whole = len(left) == len(raw) and bool(same.all())  # one layout for all: no gather
                    groups.append((layout, rows[left[same]], raw if whole else raw[left[same]]))
                left = left[~same]
        used = ~bad
        if not used.any():
            return None
        seen = {name for g in groups for name in g[0].names} | {name for s in singles for name in s[1]}
        joints = tuple(j for j in self.joints if j in seen)
        column = {name: i for i, name in enumerate(joints)}
        positions = np.full((n, len(joints)), np.nan)
        header = np.zeros(n, dtype=np.int64)
        for layout, rows, raw in groups:
            header[rows] = stamps_ns(raw[:, STAMP].tobytes())
            keep = [i for i, name in enumerate(layout.names) if name in column]
            if keep:
                values = raw[:, layout.positions : layout.end].copy().view("<f8")
                if keep != list(range(values.shape[1])):
                    values = values[:, keep]
                nonfinite = ~np.isfinite(values)
                if nonfinite.any():
                    self.nonfinite += int(np.count_nonzero(nonfinite.any(axis=1)))
                    values[nonfinite] = np.nan
                columns = [column[layout.names[i]] for i in keep]
                if len(rows) == n and columns == list(range(len(joints))):  # every message, every joint, in order
                    positions[...] = values
                else:
                    positions[rows[:, None], columns] = values
        for row, names, values, stamp_ns in singles:
            header[row] = stamp_ns
            self.nonfinite += int(not np.isfinite(values).all())
            for name, value in zip(names, values, strict=True):
                if name in column:
                    positions[row, column[name]] = value if np.isfinite(value) else np.nan
                elif name not in self._column and len(self.unknown) < MAX_UNKNOWN:
                    self.unknown.add(name)
        times_ns: I64 = block.times_ns if self.time == "receive" else header
        if bad.any():
            times_ns, positions = times_ns[used], positions[used]
        return SampleChunk(np.ascontiguousarray(times_ns), joints, positions)

    def _single(self, data: bytes | memoryview) -> tuple[tuple[str, ...], F64, int] | None:
        """A message no byte layout fits, through rosbags (None: it cannot be used; counted)."""
        try:
            names, positions, stamp_ns = self._generic(data)
        except (BagError, MsgError):
            self.undecodable += 1
            return None
        if len(names) != len(positions):
            self.skipped += 1
            return None
        return names, positions, stamp_ns

    def _generic(self, data: bytes | memoryview) -> tuple[tuple[str, ...], F64, int]:
        msg = self._deserialize(data, JOINT_STATE)
        stamp = msg.header.stamp
        return tuple(msg.name), np.asarray(msg.position, dtype=np.float64), int(stamp.sec) * 10**9 + int(stamp.nanosec)


def _matrix(buf: npt.NDArray[np.uint8], starts: I64, length: int) -> npt.NDArray[np.uint8]:
    """Messages of one ``length`` as rows of a byte matrix: a strided view when they lie evenly spaced (one
    publisher's messages back to back), else one gather."""
    if len(starts) > 1:
        step = np.diff(starts)
        if step[0] >= length and bool(np.all(step == step[0])):
            first = int(starts[0])
            view: npt.NDArray[np.uint8] = np.lib.stride_tricks.as_strided(
                buf[first:], shape=(len(starts), length), strides=(int(step[0]), 1), writeable=False
            )
            return view
    gathered: npt.NDArray[np.uint8] = buf[starts[:, None] + np.arange(length)]
    return gathered


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
