"""Block decoders (issue 46): the messages of one topic in a window decoded together, with numpy over their CDR
bytes, into arrays of what :mod:`r2d2_viz.msgs.telemetry` decodes one message at a time (no Python object per
message).

``sensor_msgs/msg/Imu`` has a fixed layout past its header's ``frame_id`` string: stamp (int32 sec, uint32 nanosec),
the string (uint32 length with its NUL, the bytes), padding to 8, then 37 doubles — orientation ``xyzw``, its
covariance (9), angular velocity (3), its covariance (9), linear acceleration (3), its covariance (9). The messages
are grouped by byte order and frame_id length, each group read as one ``(n, size)`` byte array and every field as a
column of it. A block decoder returns None for anything it does not read exactly as rosbags' deserializer would (a
length that does not match, an unknown encapsulation, a string without its NUL or not UTF-8): the caller then
decodes those messages one at a time, with the per-message decoders' clear errors.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from r2d2_viz.msgs.geometry import frame_of
from r2d2_viz.msgs.shapes import DecodeOptions
from r2d2_viz.msgs.telemetry import IMU_AXIS, quat_norm

_ENDIAN = {b"\x00\x01": "<", b"\x00\x00": ">"}
"""CDR encapsulation (representation id, first two bytes): little-endian CDR, big-endian CDR; options must be 0."""
_IMU_DOUBLES = 4 + 9 + 3 + 9 + 3 + 9


@runtime_checkable
class MessageBlock(Protocol):
    """What a block decoder returns: a row per message, cut with :meth:`sliced`."""

    def __len__(self) -> int: ...

    def sliced(self, start: int, stop: int) -> MessageBlock:
        """The rows ``start:stop``."""
        ...


@dataclass(frozen=True, eq=False)
class ImuBlock:
    """``n`` Imu messages as columns, in the order given."""

    stamps_ns: np.ndarray
    """(n,) int64: the header's stamp."""
    frames: tuple[str, ...]
    """The distinct frame ids (a leading '/' dropped, as tf2 keys them)."""
    frame_index: np.ndarray
    """(n,) int64: each message's frame id, an index into ``frames``."""
    orientation: np.ndarray
    """(n, 4) float64, ``xyzw`` as the message holds it."""
    orientation_covariance0: np.ndarray
    """(n,) float64: ``orientation_covariance[0]`` (-1: no orientation)."""
    angular_velocity: np.ndarray
    """(n, 3) float64."""
    linear_acceleration: np.ndarray
    """(n, 3) float64."""

    def __len__(self) -> int:
        return len(self.stamps_ns)

    def sliced(self, start: int, stop: int) -> ImuBlock:
        rows = slice(start, stop)
        cut = {f.name: getattr(self, f.name)[rows] for f in dataclasses.fields(self) if f.name != "frames"}
        return dataclasses.replace(self, **cut)

    def axes(self) -> tuple[np.ndarray, np.ndarray]:
        """Which messages draw their orientation (as :func:`~r2d2_viz.msgs.telemetry.decode_imu`: its norm finite
        and above 1e-9, ``orientation_covariance[0]`` not -1), and those messages' x, y, z axes ``(m, 3, 3)``
        float32, each row an axis :data:`~r2d2_viz.msgs.telemetry.IMU_AXIS` long — the per-message decoder's
        arithmetic, element for element."""
        q = self.orientation
        with np.errstate(all="ignore"):
            norm = quat_norm(q)
            drawn = np.isfinite(norm) & (norm > 1e-9) & (self.orientation_covariance0 != -1.0)
            u = q[drawn] / norm[drawn][:, None]
            x, y, z, w = u[:, 0], u[:, 1], u[:, 2], u[:, 3]
            rotation = np.empty((len(u), 3, 3), dtype=np.float64)  # geometry.quat_matrix, vectorised
            rotation[:, 0, 0] = 1 - 2 * (y * y + z * z)
            rotation[:, 0, 1] = 2 * (x * y - z * w)
            rotation[:, 0, 2] = 2 * (x * z + y * w)
            rotation[:, 1, 0] = 2 * (x * y + z * w)
            rotation[:, 1, 1] = 1 - 2 * (x * x + z * z)
            rotation[:, 1, 2] = 2 * (y * z - x * w)
            rotation[:, 2, 0] = 2 * (x * z - y * w)
            rotation[:, 2, 1] = 2 * (y * z + x * w)
            rotation[:, 2, 2] = 1 - 2 * (x * x + y * y)
            axes = (np.swapaxes(rotation, 1, 2) * IMU_AXIS).astype(np.float32)
        return drawn, axes


BlockDecoder = Callable[[Sequence[bytes | memoryview], DecodeOptions], MessageBlock | None]


def _imu_size(frame_length: int) -> int:
    """An Imu's CDR size with a frame_id of ``frame_length`` bytes (its NUL counted)."""
    return 4 + (12 + frame_length + 7) // 8 * 8 + 8 * _IMU_DOUBLES


def decode_imu_block(messages: Sequence[bytes | memoryview], options: DecodeOptions) -> ImuBlock | None:
    """``messages`` (CDR bytes of ``sensor_msgs/msg/Imu``) as one :class:`ImuBlock`, or None when one of them is
    not exactly what its layout says."""
    n = len(messages)
    groups: dict[tuple[str, int], list[int]] = {}
    for i, data in enumerate(messages):
        head = bytes(data[:16])
        endian = _ENDIAN.get(head[:2])
        if endian is None or len(head) < 16 or head[2:4] != b"\x00\x00":
            return None
        length = int.from_bytes(head[12:16], "little" if endian == "<" else "big")
        if length < 1 or len(data) != _imu_size(length):
            return None
        groups.setdefault((endian, length), []).append(i)
    stamps = np.zeros(n, dtype=np.int64)
    frame_index = np.zeros(n, dtype=np.int64)
    doubles = np.zeros((n, _IMU_DOUBLES), dtype=np.float64)
    frames: dict[str, int] = {}
    for (endian, length), rows in groups.items():
        size = _imu_size(length)
        raw = np.frombuffer(b"".join(messages[i] for i in rows), dtype=np.uint8).reshape(len(rows), size)
        index = np.asarray(rows, dtype=np.int64)
        sec = np.ascontiguousarray(raw[:, 4:8]).view(f"{endian}i4")[:, 0].astype(np.int64)
        nanosec = np.ascontiguousarray(raw[:, 8:12]).view(f"{endian}u4")[:, 0].astype(np.int64)
        stamps[index] = sec * 1_000_000_000 + nanosec
        text = raw[:, 16 : 16 + length]
        if (text[:, -1] != 0).any():
            return None
        names, inverse = np.unique(np.ascontiguousarray(text).view(f"V{length}")[:, 0], return_inverse=True)
        for k, name in enumerate(names):
            try:
                frame = frame_of(bytes(name)[:-1].decode("utf-8"))
            except UnicodeDecodeError:
                return None
            frame_index[index[inverse.reshape(-1) == k]] = frames.setdefault(frame, len(frames))
        start = size - 8 * _IMU_DOUBLES
        doubles[index] = np.ascontiguousarray(raw[:, start:]).view(f"{endian}f8")
    return ImuBlock(
        stamps_ns=stamps,
        frames=tuple(frames),
        frame_index=frame_index,
        orientation=doubles[:, 0:4],
        orientation_covariance0=doubles[:, 4],
        angular_velocity=doubles[:, 13:16],
        linear_acceleration=doubles[:, 25:28],
    )
