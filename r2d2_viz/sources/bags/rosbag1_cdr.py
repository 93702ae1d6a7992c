"""ROS 1 messages of one connection converted to CDR many at a time: messages of the same shape (the same length
and the same string and sequence lengths: a JointState stream with fixed names, IMU, odometry, most tf) differ only
in the bytes they copy, so the first is converted by rosbags and its conversion becomes a byte map (which input
byte lands where), applied to all the others as one numpy gather; a second message is converted by rosbags as well
and must come out identical, or the batch is converted one message at a time.

Pure: no rerun import.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from r2d2_viz.msgs.definitions import from_ros1, own_store
from r2d2_viz.msgs.typestore import MsgError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

MIN_BATCH = 8
"""Fewer messages of one shape are converted one by one."""
MAX_BATCHED_BYTES = 1 << 16
"""Bigger messages are converted one by one (their cost is their bytes' copy, not the call)."""
_SIZES = {"bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "octet": 1, "int16": 2, "uint16": 2}
_SIZES |= {"int32": 4, "uint32": 4, "float32": 4, "int64": 8, "uint64": 8, "float64": 8}


class _ShapeError(Exception):
    """The message does not fit its definition (the plan is abandoned)."""


class _Plan:
    """Walks one ROS 1 message of a type, noting the bytes copied to CDR and the length fields read."""

    def __init__(self, store: Typestore, raw: bytes) -> None:
        self.store, self.raw = store, raw
        self.src, self.dst, self.lengths = 0, 0, []  # type: ignore[var-annotated]
        self.copies: list[tuple[int, int, int]] = []

    def _copy(self, n: int) -> None:
        if self.src + n > len(self.raw):
            raise _ShapeError
        self.copies.append((self.src, self.dst, n))
        self.src += n
        self.dst += n

    def _align(self, n: int) -> None:
        self.dst += -self.dst % n

    def _length(self) -> int:
        if self.src + 4 > len(self.raw):
            raise _ShapeError
        self.lengths.append(self.src)
        (n,) = struct.unpack_from("<I", self.raw, self.src)
        self.src += 4
        self._align(4)
        self.dst += 4
        return int(n)

    def message(self, typename: str) -> None:
        if typename == "std_msgs/msg/Header":
            self.src += 4  # ROS 1's seq, which ROS 2 dropped
        for _, desc in self.store.fielddefs[typename][1]:
            self.field(desc)

    def field(self, desc: Any) -> None:
        kind, rest = desc
        if kind == 1:
            self.base(rest[0], 1)
        elif kind == 2:
            self.message(rest)
        elif kind == 3:
            self.items(rest[0], rest[1])
        else:
            self.items(rest[0], self._length())

    def base(self, name: str, count: int) -> None:
        if name == "string":
            for _ in range(count):
                n = self._length()
                self._copy(n)
                self.dst += 1  # the NUL CDR adds
            return
        if name not in _SIZES:
            raise _ShapeError
        self._align(_SIZES[name])
        self._copy(_SIZES[name] * count)

    def items(self, sub: Any, count: int) -> None:
        if count > len(self.raw):
            raise _ShapeError
        if sub[0] == 1:
            if count:
                self.base(sub[1][0], count)
            return
        for _ in range(count):
            self.field(sub)


def byte_map(
    store: Typestore, typename: str, raw: bytes, convert: Callable[[bytes | memoryview], memoryview]
) -> tuple[bytes, np.ndarray, np.ndarray, np.ndarray]:
    """For one message: its CDR conversion, the input offsets copied, where they land, and the offsets of the
    input's length fields. Checked on a probe (the message with every copied byte changed, converted by rosbags):
    the changed bytes must land where the map says, and nothing else change. Raises ``ValueError`` otherwise."""
    plan = _Plan(store, raw)
    try:
        plan.message(typename)
    except (_ShapeError, KeyError, RecursionError):
        raise ValueError(f"{typename}: no byte map") from None
    if plan.src != len(raw):
        raise ValueError(f"{typename}: no byte map")
    empty = np.zeros(0, np.int64)
    src = np.concatenate([np.arange(s, s + n) for s, _, n in plan.copies] or [empty]).astype(np.int64)
    dst = np.concatenate([np.arange(d, d + n) for _, d, n in plan.copies] or [empty]).astype(np.int64) + 4
    lengths = np.concatenate([np.arange(p, p + 4) for p in plan.lengths] or [empty]).astype(np.int64)
    cdr = np.frombuffer(bytes(convert(raw)), np.uint8)
    probe = np.frombuffer(raw, np.uint8).copy()
    probe[src] = (np.frombuffer(raw, np.uint8)[src].astype(np.int64) + 1 + np.arange(len(src)) % 251) % 256
    cdr_probe = np.frombuffer(bytes(convert(probe.tobytes())), np.uint8)
    if len(cdr_probe) != len(cdr) or (len(dst) and int(dst.max()) >= len(cdr)):
        raise ValueError(f"{typename}: no byte map")
    same = np.ones(len(cdr), dtype=bool)
    same[dst] = False
    if not (np.array_equal(cdr_probe[dst], probe[src]) and np.array_equal(cdr_probe[same], cdr[same])):
        raise ValueError(f"{typename}: no byte map")
    return cdr.tobytes(), src, dst, lengths


def convert_batch(
    store: Typestore,
    typename: str,
    convert: Callable[[bytes | memoryview], memoryview],
    raws: np.ndarray,
) -> np.ndarray | None:
    """``raws`` (n, L): n ROS 1 messages of one length as rows; their CDR as rows of one (n, M) array when they all
    have the first one's shape and a check on the last passes, else None (convert them one by one). Raises what
    ``convert`` raises."""
    try:
        cdr, src, dst, lengths = byte_map(store, typename, bytes(raws[0]), convert)
    except ValueError:
        return None
    if lengths.size and not np.all(raws[:, lengths] == raws[0, lengths]):
        return None
    out = np.tile(np.frombuffer(cdr, np.uint8), (len(raws), 1))
    out[:, dst] = raws[:, src]
    last = len(raws) - 1
    if not np.array_equal(out[last], np.frombuffer(bytes(convert(bytes(raws[last]))), np.uint8)):
        return None
    return out


def convert_runs(
    buf: np.ndarray, conn_ids: np.ndarray, starts: np.ndarray, ends: np.ndarray, types: dict[int, tuple[str, str]]
) -> dict[int, memoryview]:
    """For messages ``buf[starts[i]:ends[i]]`` on connections ``conn_ids[i]`` (of ``types[c]``: type name and ROS 1
    definition): the CDR of those converted many at a time (runs of one connection and one length of at least
    :data:`MIN_BATCH` small messages that :func:`convert_batch` takes), by row; the caller converts the others."""
    done: dict[int, memoryview] = {}
    lengths = ends - starts
    small = lengths <= MAX_BATCHED_BYTES
    for c in np.unique(conn_ids).tolist():
        mine = (conn_ids == c) & small
        values, counts = np.unique(lengths[mine], return_counts=True)
        for length in values[counts >= MIN_BATCH].tolist():
            rows = np.flatnonzero(mine & (lengths == length))
            msgtype, definition = types[c]
            try:
                store, convert = own_store(msgtype, definition, "ros1msg"), from_ros1(msgtype, definition)
                cdr = convert_batch(store, msgtype, convert, buf[starts[rows, None] + np.arange(length)])
            except MsgError:
                cdr = None
            if cdr is not None:
                done.update(zip(rows.tolist(), (row.data for row in cdr), strict=True))
    return done
