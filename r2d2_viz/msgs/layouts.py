"""Where the fields of a CDR-encoded ``sensor_msgs/msg/JointState`` and ``tf2_msgs/msg/TFMessage`` sit, so that
many messages can be decoded (or encoded) with a few numpy calls instead of one deserializer call each.

A ROS 2 message on the wire (and in a bag) is a 4-byte encapsulation header (``00 01``: little-endian CDR) and
then the fields in order; each primitive is aligned to its size, counted from the end of that header; strings
are a ``uint32`` length (with the terminating NUL) and the bytes; sequences a ``uint32`` count and the items.
Messages from one publisher share a *layout*: the same frame names and joint names, so the same offsets, and
only the stamps and the numbers differ. A layout's :attr:`key` is the bytes from the end of the stamp to the
end of the last name (and count), so a message has that layout exactly when its bytes there equal the key.

Pure: ``struct`` and numpy. Anything not little-endian CDR, or malformed, raises ``ValueError`` (callers then
use the generic deserializer of ``rosbags``, which reports what is wrong). An Odometry's pose (either byte order)
is read where it sits, after the header and ``child_frame_id``: NaN when the bytes are not an Odometry.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from r2d2_viz.arrays import F64

_U32 = struct.Struct("<I")
CDR_LE = b"\x00\x01"
_NAN_POSE = np.full(7, np.nan)
STAMP = slice(4, 12)
"""``header.stamp`` (``int32 sec``, ``uint32 nanosec``) of a JointState: right after the encapsulation header."""


def _align(offset: int, size: int) -> int:
    return offset + (-(offset - 4)) % size


class _Cursor:
    def __init__(self, data: bytes | memoryview) -> None:
        if len(data) < 8 or bytes(data[:2]) != CDR_LE:
            raise ValueError("not little-endian CDR")
        self.data, self.offset = data, 4

    def u32(self) -> int:
        self.offset = _align(self.offset, 4)
        if self.offset + 4 > len(self.data):
            raise ValueError("message ends early")
        (value,) = _U32.unpack_from(self.data, self.offset)
        self.offset += 4
        return int(value)

    def string(self) -> str:
        length = self.u32()
        end = self.offset + length
        if length == 0 or end > len(self.data) or self.data[end - 1] != 0:
            raise ValueError("bad string")
        text = bytes(self.data[self.offset : end - 1]).decode("utf-8")
        self.offset = end
        return text

    def skip(self, size: int) -> None:
        self.offset += size
        if self.offset > len(self.data):
            raise ValueError("message ends early")

    def doubles(self, count: int) -> int:
        """The offset of ``count`` float64 here (aligned), and skip them."""
        if count:
            self.offset = _align(self.offset, 8)
        start = self.offset
        self.skip(8 * count)
        return start


@dataclass(frozen=True)
class JointStateLayout:
    """One JointState layout: ``names``, and ``count`` positions at ``positions`` (offset of the first)."""

    key: bytes
    frame_id: str
    names: tuple[str, ...]
    count: int
    positions: int

    @property
    def end(self) -> int:
        """Where the positions end: a message of this layout is at least this long."""
        return self.positions + 8 * self.count

    def matches(self, data: bytes | memoryview) -> bool:
        return len(data) >= self.end and data[12 : 12 + len(self.key)] == self.key


def joint_state_layout(data: bytes | memoryview) -> JointStateLayout:
    """Parse one JointState's layout (its velocity and effort are checked for length, not read)."""
    c = _Cursor(data)
    c.skip(8)  # header.stamp
    frame_id = c.string()
    names = tuple(c.string() for _ in range(c.u32()))
    count = c.u32()
    key_end = c.offset
    positions = c.doubles(count)
    for _ in range(2):  # velocity, effort
        c.doubles(c.u32())
    return JointStateLayout(bytes(data[12:key_end]), frame_id, names, count, positions)


@dataclass(frozen=True)
class TfLayout:
    """One TFMessage layout: per transform, its frames and the offsets of its stamp and translation (the
    rotation ``x, y, z, w`` follows the translation)."""

    key: bytes
    parents: tuple[str, ...]
    children: tuple[str, ...]
    stamps: tuple[int, ...]
    translations: tuple[int, ...]
    end: int

    def matches(self, data: bytes | memoryview) -> bool:
        if len(data) < self.end:
            return False
        # the names and counts lie between the numbers: compare all bytes but the stamps and the doubles
        start = 4
        for stamp, translation in zip(self.stamps, self.translations, strict=True):
            if data[start:stamp] != self.key[start - 4 : stamp - 4]:
                return False
            if data[stamp + 8 : translation] != self.key[stamp + 4 : translation - 4]:
                return False
            start = translation + 56
        return data[start : self.end] == self.key[start - 4 : self.end - 4]  # the count of an empty message


def tf_layout(data: bytes | memoryview) -> TfLayout:
    """Parse one TFMessage's layout."""
    c = _Cursor(data)
    parents: list[str] = []
    children: list[str] = []
    stamps: list[int] = []
    translations: list[int] = []
    for _ in range(c.u32()):
        c.offset = _align(c.offset, 4)
        stamps.append(c.offset)
        c.skip(8)
        parents.append(c.string())
        children.append(c.string())
        translations.append(c.doubles(7))
    return TfLayout(
        bytes(data[4 : c.offset]), tuple(parents), tuple(children), tuple(stamps), tuple(translations), c.offset
    )


def odometry_pose(data: bytes | memoryview) -> F64:
    """An Odometry's ``pose.pose`` as ``(x, y, z, qx, qy, qz, qw)`` (float64) from its CDR bytes; all NaN when the
    bytes are not a readable Odometry (its decoder then says what is wrong)."""
    if len(data) < 12 or data[0] != 0 or data[1] not in (0, 1):
        return _NAN_POSE
    order = "<" if data[1] == 1 else ">"
    offset = 4 + 8  # encapsulation header, header.stamp
    for _ in range(2):  # header.frame_id, child_frame_id
        offset += -(offset - 4) % 4
        if offset + 4 > len(data):
            return _NAN_POSE
        (length,) = struct.unpack_from(order + "I", data, offset)
        offset += 4 + length
    offset += -(offset - 4) % 8
    if offset + 56 > len(data):
        return _NAN_POSE
    return np.frombuffer(data, dtype=order + "f8", count=7, offset=offset).astype(np.float64)


def odometry_poses(messages: Sequence[bytes | memoryview]) -> F64:
    """:func:`odometry_pose` of each message, one row each: ``(n, 7)``."""
    return np.array([odometry_pose(m) for m in messages], dtype=np.float64).reshape(-1, 7)
