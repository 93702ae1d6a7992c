"""MarkerArrays decoded a block at a time (issue 46, item 3): the messages of one topic in a window read together with
numpy over their CDR bytes, not one rosbags deserialisation each (which cost as much as the rest of the run).

The trick is :mod:`r2d2_viz.msgs.layouts`'s: arrays from one publisher share a *layout* — as many markers, the same
string and sequence lengths — hence the same byte offset for every field. One message's layout is walked in Python
(CDR rules: each primitive aligned to its size from the end of the 4-byte encapsulation header, either byte order;
Humble's ``Marker``, the one every bag's definition is converted to by :mod:`r2d2_viz.msgs.definitions`); every
message of the same size and encapsulation whose length fields hold the same numbers at those offsets has that
layout exactly (the lengths decide every later offset), so each field of every marker of the group is a gather of
the group's bytes (poses, scales, colours, types, actions, ids, lifetimes, stamps, points, colours per point) and
strings are decoded once per distinct value. A message whose layout differs gets its own walk; one the walk cannot
read (a bad length, truncated bytes, a string without its NUL, invalid UTF-8 in any string, another
encapsulation: what rosbags refuses) is marked ``bad``: the caller decodes it alone, with today's per-message errors.

Pure: numpy and ``struct``.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from r2d2_viz.msgs.shapes import DecodeOptions

I64 = npt.NDArray[np.int64]
I32 = npt.NDArray[np.int32]
F64 = npt.NDArray[np.float64]
F32 = npt.NDArray[np.float32]
Bools = npt.NDArray[np.bool_]
Texts = npt.NDArray[np.object_]
_CDR = (b"\x00\x00", b"\x00\x01")  # big-endian, little-endian CDR (encapsulation kinds 0 and 1)
_FEW = 8
"""Messages of one layout up to this many: their strings are decoded one by one (numpy's unique costs more)."""
MAX_MARKERS = 1 << 20
"""More markers than this in one array: not read here (the per-message decoder says what is wrong)."""


@dataclass(frozen=True, eq=False)
class MarkerBlock:
    """The markers of a topic's messages, flat in message order (``first[i]:first[i + 1]`` are message ``i``'s;
    none for a ``bad`` one). Quaternions as the message gives them (``xyzw``, not normalised); colours 0..1."""

    bad: Bools
    first: I64
    frame: Texts
    stamp_ns: I64
    ns: Texts
    id: I32
    type: I32
    action: I32
    pose: F64
    """``(n, 7)``: position x, y, z and orientation x, y, z, w."""
    scale: F64
    color: F32
    lifetime_ns: I64
    frame_locked: Bools
    points_at: I64
    """``points[points_at[j]:points_at[j + 1]]`` are marker ``j``'s points ``(P, 3)``; likewise ``colors_at``."""
    points: F64
    colors_at: I64
    colors: F32
    text: Texts
    mesh_resource: Texts
    embedded: Bools
    """``mesh_use_embedded_materials``."""


@dataclass
class _Layout:
    """Where one message's fields sit: per marker, the offset of each fixed field and each string's (offset,
    length with its NUL) and each sequence's (offset, count)."""

    size: int
    little: bool
    lengths_at: list[int] = field(default_factory=list)
    lengths: list[int] = field(default_factory=list)
    nuls: list[int] = field(default_factory=list)
    fixed: dict[str, list[int]] = field(default_factory=dict)
    strings: dict[str, list[tuple[int, int]]] = field(default_factory=dict)
    seqs: dict[str, list[tuple[int, int]]] = field(default_factory=dict)


def _walk(data: bytes) -> _Layout:
    """One message's layout (``ValueError`` on anything it cannot read): one loop, no call per fixed field."""
    size, head = len(data), data[:2]
    if size < 8 or head not in _CDR:
        raise ValueError("not plain CDR")
    layout = _Layout(size, head == _CDR[1])
    u32 = struct.Struct("<I" if layout.little else ">I").unpack_from
    at, values, nuls = layout.lengths_at, layout.lengths, layout.nuls
    stamp: list[int] = []
    ints: list[int] = []
    pose: list[int] = []
    embedded: list[int] = []
    spans: dict[str, list[tuple[int, int]]] = {name: [] for name in ("frame", "ns", "text", "mesh", "other", "points")}
    frame, ns, text, mesh, other, points = spans.values()
    colors: list[tuple[int, int]] = []

    def count(pos: int) -> tuple[int, int]:
        pos += (-(pos - 4)) % 4
        if pos + 4 > size:
            raise ValueError("ends early")
        (n,) = u32(data, pos)
        at.append(pos)
        values.append(n)
        return pos + 4, int(n)

    def string(pos: int, spans: list[tuple[int, int]]) -> int:
        pos, n = count(pos)
        end = pos + n
        if n == 0 or end > size or data[end - 1] != 0:
            raise ValueError("a string without its NUL")
        nuls.append(end - 1)
        spans.append((pos, n))
        return end

    pos, markers = count(4)
    if markers > min(MAX_MARKERS, size):
        raise ValueError("absurd marker count")
    for _ in range(markers):
        pos += (-(pos - 4)) % 4
        stamp.append(pos)
        pos = string(string(pos + 8, frame), ns)
        pos += (-(pos - 4)) % 4
        ints.append(pos)  # id, type, action
        pos += 12
        pos += (-(pos - 4)) % 8
        pose.append(pos)  # then scale, color, lifetime, frame_locked: 56 + 24 + 16 + 8 + 1 bytes
        pos, n = count(pos + 105)
        if n:
            pos += (-(pos - 4)) % 8
        points.append((pos, n))
        pos, n = count(pos + 24 * n)
        colors.append((pos, n))
        pos = string(pos + 16 * n, other)  # texture_resource
        pos += (-(pos - 4)) % 4
        pos = string(string(pos + 8, other), other)  # texture: stamp, frame_id, format
        pos, n = count(pos)  # texture.data
        pos, n = count(pos + n)  # uv_coordinates
        pos = string(string(pos + 8 * n, text), mesh)
        pos, n = count(string(pos, other))  # mesh_file: filename, data
        embedded.append(pos + n)
        pos += n + 1
    if pos > size:
        raise ValueError("ends early")
    layout.fixed = {"stamp": stamp, "ints": ints, "pose": pose, "embedded": embedded}
    layout.strings = {name: spans[name] for name in ("frame", "ns", "text", "mesh", "other")}
    layout.seqs = {"points": points, "colors": colors}
    return layout


def _gather(rows: npt.NDArray[np.uint8], at: list[int], size: int, dtype: str) -> npt.NDArray[Any]:
    """The ``size`` bytes at each offset of every row, as ``dtype``: ``(k, len(at), size // itemsize)``."""
    index = np.asarray(at, dtype=np.int64)[:, None] + np.arange(size)
    block = np.ascontiguousarray(rows[:, index])
    return block.view(dtype)


def _texts(rows: npt.NDArray[np.uint8], spans: list[tuple[int, int]], bad: Bools) -> Texts:
    """Each span's string (without its NUL) of every row, ``(k, len(spans))``; rows whose bytes are not UTF-8
    are marked in ``bad``."""
    out = np.empty((rows.shape[0], len(spans)), dtype=object)
    if rows.shape[0] <= _FEW:  # a layout of its own: each string decoded where it is
        for r, row in enumerate(rows):
            data = row.tobytes()
            for j, (start, n) in enumerate(spans):
                try:
                    out[r, j] = data[start : start + n - 1].decode("utf-8")
                except UnicodeDecodeError:
                    out[r, j], bad[r] = "", True
        return out
    for j, (start, n) in enumerate(spans):
        if n == 1:
            out[:, j] = ""
            continue
        raw = np.ascontiguousarray(rows[:, start : start + n - 1]).view(f"V{n - 1}").ravel()
        values, inverse = np.unique(raw, return_inverse=True)
        texts: list[str] = []
        for k, value in enumerate(values):
            try:
                texts.append(value.tobytes().decode("utf-8"))
            except UnicodeDecodeError:
                texts.append("")
                bad[inverse == k] = True
        out[:, j] = np.array(texts, dtype=object)[inverse]
    return out


@dataclass
class _Part:
    """One layout's messages (their indices) and their fields, ``(k, markers, …)``."""

    index: I64
    fields: dict[str, npt.NDArray[Any]]
    points: F64  # (k, P, 3): every marker's points, marker after marker
    point_counts: I64  # (markers,)
    colors: F32
    color_counts: I64


def _part(rows: npt.NDArray[np.uint8], index: I64, layout: _Layout, bad: Bools) -> _Part:
    e = "<" if layout.little else ">"
    f = dict(layout.fixed)
    for name, after_pose in (("scale", 56), ("color", 80), ("lifetime", 96), ("locked", 104)):
        f[name] = [p + after_pose for p in f["pose"]]
    ints = _gather(rows, f["ints"], 12, e + "i4")
    stamp = _gather(rows, f["stamp"], 8, e + "u4").astype(np.int64)
    life = _gather(rows, f["lifetime"], 8, e + "u4").astype(np.int64)
    stamp[..., 0] = stamp[..., 0].astype(np.uint32).view(np.int32)  # sec is int32
    life[..., 0] = life[..., 0].astype(np.uint32).view(np.int32)
    local_bad = np.zeros(len(index), dtype=bool)
    fields: dict[str, npt.NDArray[Any]] = {
        "id": ints[..., 0],
        "type": ints[..., 1],
        "action": ints[..., 2],
        "stamp_ns": stamp[..., 0] * 1_000_000_000 + stamp[..., 1],
        "lifetime_ns": life[..., 0] * 1_000_000_000 + life[..., 1],
        "pose": _gather(rows, f["pose"], 56, e + "f8"),
        "scale": _gather(rows, f["scale"], 24, e + "f8"),
        "color": _gather(rows, f["color"], 16, e + "f4"),
        "frame_locked": _gather(rows, f["locked"], 1, "u1")[..., 0] != 0,
        "embedded": _gather(rows, f["embedded"], 1, "u1")[..., 0] != 0,
    }
    for name in ("frame", "ns", "text", "mesh"):
        fields[name] = _texts(rows, layout.strings.get(name, []), local_bad)
    _texts(rows, layout.strings.get("other", []), local_bad)  # not drawn, but UTF-8 (or rosbags refuses them)
    bad[index[local_bad]] = True
    seq: dict[str, tuple[npt.NDArray[Any], I64]] = {}
    for name, item, width, kind in (("points", 24, 3, "f8"), ("colors", 16, 4, "f4")):
        spans = layout.seqs.get(name, [])
        counts = np.array([n for _, n in spans], dtype=np.int64)
        at = [start + i * item for start, n in spans for i in range(n)]
        values = _gather(rows, at, item, e + kind) if at else np.zeros((len(index), 0, width), dtype=e + kind)
        seq[name] = (values.reshape(len(index), -1, width), counts)
    return _Part(index, fields, seq["points"][0], seq["points"][1], seq["colors"][0], seq["colors"][1])


def _parts(messages: Sequence[bytes | memoryview], bad: Bools) -> list[_Part]:
    by_size: dict[tuple[int, bytes], list[int]] = {}
    datas = [bytes(m) for m in messages]
    for i, data in enumerate(datas):
        by_size.setdefault((len(data), data[:2]), []).append(i)
    parts: list[_Part] = []
    for members in by_size.values():
        todo = np.asarray(members, dtype=np.int64)
        rows = np.frombuffer(b"".join(datas[i] for i in members), dtype=np.uint8).reshape(len(members), -1)
        left = np.arange(len(members))
        while len(left):
            try:
                layout = _walk(datas[int(todo[left[0]])])
            except (ValueError, struct.error):
                bad[todo[left[0]]] = True
                left = left[1:]
                continue
            mine = rows[left]
            lengths = _gather(mine, layout.lengths_at, 4, ("<" if layout.little else ">") + "u4")[..., 0]
            same = np.all(lengths == np.asarray(layout.lengths, dtype=np.uint32), axis=1)
            if layout.nuls:
                same &= np.all(mine[:, layout.nuls] == 0, axis=1)
            same[0] = True  # the one walked (its NULs checked): the loop always ends
            parts.append(_part(mine[same], todo[left[same]], layout, bad))
            left = left[~same]
    return parts


def decode_marker_arrays(messages: Sequence[bytes | memoryview], options: DecodeOptions | None = None) -> MarkerBlock:
    """One topic's MarkerArray messages (CDR, Humble's layout) as one :class:`MarkerBlock`."""
    bad = np.zeros(len(messages), dtype=bool)
    parts = _parts(messages, bad)
    counts = np.zeros(len(messages), dtype=np.int64)
    for part in parts:
        counts[part.index] = len(part.point_counts)
    counts[bad] = 0
    first = np.zeros(len(messages) + 1, dtype=np.int64)
    np.cumsum(counts, out=first[1:])
    n = int(first[-1])
    out: dict[str, npt.NDArray[Any]] = {
        "frame": np.empty(n, dtype=object),
        "ns": np.empty(n, dtype=object),
        "text": np.empty(n, dtype=object),
        "mesh": np.empty(n, dtype=object),
        "stamp_ns": np.zeros(n, dtype=np.int64),
        "lifetime_ns": np.zeros(n, dtype=np.int64),
        "id": np.zeros(n, dtype=np.int32),
        "type": np.zeros(n, dtype=np.int32),
        "action": np.zeros(n, dtype=np.int32),
        "pose": np.zeros((n, 7)),
        "scale": np.zeros((n, 3)),
        "color": np.zeros((n, 4), dtype=np.float32),
        "frame_locked": np.zeros(n, dtype=bool),
        "embedded": np.zeros(n, dtype=bool),
    }
    point_counts = np.zeros(n, dtype=np.int64)
    color_counts = np.zeros(n, dtype=np.int64)
    placed: list[tuple[I64, _Part, Bools]] = []
    for part in parts:
        keep = ~bad[part.index]
        m = len(part.point_counts)
        if not keep.any() or m == 0:
            continue
        at = (first[part.index[keep]][:, None] + np.arange(m)).ravel()
        for name, column in out.items():
            value = part.fields[name][keep]
            column[at] = value.reshape(len(at), *column.shape[1:])
        point_counts[at] = np.tile(part.point_counts, int(keep.sum()))
        color_counts[at] = np.tile(part.color_counts, int(keep.sum()))
        placed.append((at, part, keep))
    points_at = np.zeros(n + 1, dtype=np.int64)
    colors_at = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(point_counts, out=points_at[1:])
    np.cumsum(color_counts, out=colors_at[1:])
    points = np.zeros((int(points_at[-1]), 3))
    colors = np.zeros((int(colors_at[-1]), 4), dtype=np.float32)
    for at, part, keep in placed:
        m = len(part.point_counts)
        starts = at.reshape(-1, m)[:, 0]
        for dest, starts_at, values in ((points, points_at, part.points), (colors, colors_at, part.colors)):
            per = values.shape[1]
            if per:
                where = (starts_at[starts][:, None] + np.arange(per)).ravel()
                dest[where] = values[keep].reshape(-1, dest.shape[1])
    return MarkerBlock(
        bad=bad,
        first=first,
        frame=out["frame"],
        stamp_ns=out["stamp_ns"],
        ns=out["ns"],
        id=out["id"],
        type=out["type"],
        action=out["action"],
        pose=out["pose"],
        scale=out["scale"],
        color=out["color"],
        lifetime_ns=out["lifetime_ns"],
        frame_locked=out["frame_locked"],
        points_at=points_at,
        points=points,
        colors_at=colors_at,
        colors=colors,
        text=out["text"],
        mesh_resource=out["mesh"],
        embedded=out["embedded"],
    )
