"""Any message's fields as numpy columns, named as ``ros2 topic echo`` shows them (``twist.twist.linear.x``,
``effort[2]``, ``points[0].positions[1]``), decoded with nothing but the message's definition (a rosbags typestore).

A message's *layout* (:class:`Layout`) is where each of its fields sits in its CDR bytes; it depends only on its
strings' and sequences' lengths. The layout of one message is worked out by walking its definition
(:func:`walk`); the other messages of a topic are then matched to it with a few numpy comparisons (the same total
length, the same length fields at the same places), and the fields of all the messages of one layout are read as
numpy views over their bytes: no Python object per message. Messages no known layout fits are walked one by one
(their fields still gathered per field, not per message).

Long arrays (over :data:`MAX_ITEMS` numbers, over :data:`MAX_NESTED` messages or strings) and byte sequences
(``uint8[]``, ``int8[]``, ``char[]``) are summarised: ``NAME.len``, and ``NAME.min`` / ``NAME.max`` for numbers.
The items a message path names (``ranges[180]``, ``poses[80].position.x``, ``ranges[-1]``: from the end) are read
whatever the summary (``keep``: they are *picked*, :attr:`Columns.picked`).

Pure: numpy; the typestore comes from rosbags. Bad messages raise ``ValueError`` from :func:`walk`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from r2d2_viz.msgs.generic.message_path import picks

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

MAX_ITEMS = 256
"""A numeric array with more items than this is summarised (length, min, max)…"""
MAX_NESTED = 64
"""…and an array of messages or strings with more than this, by its length."""
SIZES = {"bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "octet": 1, "int16": 2, "uint16": 2}
SIZES |= {"int32": 4, "uint32": 4, "float32": 4, "int64": 8, "uint64": 8, "float64": 8}
DTYPES = {"bool": "?", "byte": "u1", "char": "u1", "octet": "u1", "int8": "i1", "uint8": "u1", "float32": "<f4"}
DTYPES |= {"int16": "<i2", "uint16": "<u2", "int32": "<i4", "uint32": "<u4", "int64": "<i8", "uint64": "<u8"}
DTYPES |= {"float64": "<f8"}
BIG = {k: v.replace("<", ">") for k, v in DTYPES.items()}
"""Big-endian CDR's."""
_BYTES = {"uint8", "int8", "byte", "char", "octet"}


@dataclass(frozen=True)
class Number:
    """A number (``count`` None) or a run of ``count`` numbers (an array: ``NAME[i]``)."""

    name: str
    dtype: str
    count: int | None = None
    summary: bool = False
    """Read as ``NAME.len``, ``NAME.min``, ``NAME.max``."""
    picked: bool = False
    """Read because a path names it (an item of a summarised array, or counted from the end)."""


@dataclass(frozen=True)
class Layout:
    """Where one message's fields sit (offsets from the start of its bytes, the CDR header included)."""

    size: int
    checks: tuple[tuple[int, int], ...]
    """``(offset, value)`` of every length field (strings, sequences): a message of this size with these values
    there has this layout."""
    numbers: tuple[Number, ...]
    offsets: tuple[int, ...]
    texts: tuple[str, ...]
    text_spans: tuple[tuple[int, int], ...]
    """``(offset, length)`` of each text (without its NUL)."""
    lengths: tuple[tuple[str, int], ...] = ()
    """Long arrays of messages or strings: ``(NAME.len, count)``."""
    little: bool = True
    """Little-endian CDR (else big)."""

    @property
    def names(self) -> tuple[object, ...]:
        """What messages of several layouts must share to be columns together (strings' lengths aside)."""
        numbers = tuple((n.name, n.dtype, None if n.summary else n.count) for n in self.numbers)
        return (numbers, self.texts, tuple(n for n, _ in self.lengths))


class _Walk:
    def __init__(self, store: Typestore, data: bytes | memoryview, keep: frozenset[str], ros1: bool) -> None:
        if len(data) < 4 or bytes(data[:2]) not in (b"\x00\x01", b"\x00\x00"):
            raise ValueError("not CDR (an unknown encapsulation)")
        self.store, self.data, self.pos, self.quiet = store, data, 4, 0
        self.keep, self.picks = keep, picks(keep)
        self.little = data[1] == 1
        self.dtypes = (DTYPES if self.little else BIG) | ({"byte": "i1"} if ros1 else {})  # ROS 1's byte: int8
        self.checks: list[tuple[int, int]] = []
        self.numbers: list[Number] = []
        self.offsets: list[int] = []
        self.texts: list[str] = []
        self.spans: list[tuple[int, int]] = []
        self.lengths: list[tuple[str, int]] = []

    def need(self, size: int) -> None:
        if self.pos + size > len(self.data):
            raise ValueError("shorter than its definition")

    def align(self, size: int) -> None:
        self.pos += -(self.pos - 4) % size

    def u32(self) -> int:
        self.align(4)
        self.need(4)
        value = int.from_bytes(self.data[self.pos : self.pos + 4], "little" if self.little else "big")
        self.checks.append((self.pos, value))
        self.pos += 4
        return value

    def message(self, msgtype: str, prefix: str) -> None:
        for name, desc in self.store.fielddefs[msgtype][1]:
            self.field(prefix + name, desc)

    def field(self, name: str, desc: Any) -> None:
        kind, rest = desc
        if kind == 2:
            self.message(rest, name + ".")
        elif kind == 1:
            self.base(name, rest[0])
        elif kind == 3:
            self.items(name, rest[0], rest[1], fixed=True)
        else:
            count = self.u32()
            if count > len(self.data) - self.pos:
                raise ValueError(f"shorter than its definition (a length field of {count})")
            self.items(name, rest[0], count, fixed=False)

    def base(self, name: str, typ: str) -> None:
        if typ in ("string", "wstring"):
            length = self.u32()
            width = 2 if typ == "wstring" else 1
            if length * width > len(self.data) - self.pos:
                raise ValueError(f"shorter than its definition (a length field of {length})")
            if typ == "string" and (length == 0 or self.data[self.pos + length - 1] != 0):
                raise ValueError("a string without its terminating NUL")
            if typ == "string" and (not self.quiet or name in self.keep):
                self.texts.append(name)
                self.spans.append((self.pos, length - 1))
            self.pos += length * width
            return
        size = SIZES[typ]
        self.align(size)
        self.need(size)
        if not self.quiet or name in self.keep:
            self.numbers.append(Number(name, self.dtypes[typ], picked=bool(self.quiet)))
            self.offsets.append(self.pos)
        self.pos += size

    def items(self, name: str, sub: Any, count: int, *, fixed: bool) -> None:
        if sub[0] == 1 and sub[1][0] not in ("string", "wstring"):
            typ = sub[1][0]
            size = SIZES[typ]
            if count:
                self.align(size)
            self.need(size * count)
            summary = count > MAX_ITEMS or (not fixed and typ in _BYTES)
            if not self.quiet:
                self.numbers.append(Number(name, self.dtypes[typ], count, summary))
                self.offsets.append(self.pos)
            if f"{name}[:]" in self.keep:  # a slice: every item, one column of rows of ``count``
                self.numbers.append(Number(f"{name}[:]", self.dtypes[typ], count, picked=True))
                self.offsets.append(self.pos)
            for k in self.picks.get(name, ()):  # items a path names that the above does not give
                i = k if k >= 0 else count + k
                if (self.quiet or summary or k < 0) and 0 <= i < count and f"{name}[{k}]" in self.keep:
                    self.numbers.append(Number(f"{name}[{k}]", self.dtypes[typ], picked=True))
                    self.offsets.append(self.pos + size * i)
            self.pos += size * count
            return
        long = count > MAX_NESTED
        if long and not self.quiet:
            self.lengths.append((f"{name}.len", count))
        from_end = {count + k: k for k in self.picks.get(name, ()) if -count <= k < 0}
        self.quiet += long
        for i in range(count):
            if i in from_end:  # walked once more under the name the path gives it, keeping only what it names
                pos, checks = self.pos, len(self.checks)
                self.quiet += 1
                self.item(f"{name}[{from_end[i]}]", sub)
                self.quiet -= 1
                self.pos = pos
                del self.checks[checks:]
            self.item(f"{name}[{i}]", sub)
        self.quiet -= long

    def item(self, name: str, sub: Any) -> None:
        if sub[0] == 1:
            self.base(name, sub[1][0])
        else:
            self.message(sub[1], name + ".")


def walk(
    store: Typestore, msgtype: str, data: bytes | memoryview, keep: frozenset[str] = frozenset(), *, ros1: bool = False
) -> Layout:
    """The layout of one message of ``msgtype`` (defined in ``store``); ``ValueError`` naming what is wrong (as
    rosbags: more than 3 bytes left over is a size mismatch). ``keep``: names read whatever the summary (the items
    paths name); ``ros1``: a ROS 1 definition (its ``byte`` is signed)."""
    w = _Walk(store, data, keep, ros1)
    try:
        w.message(msgtype, "")
    except (KeyError, IndexError) as exc:
        raise ValueError(f"cannot be read ({type(exc).__name__})") from None
    if w.pos + 3 < len(data):
        raise ValueError("longer than its definition (size mismatch)")
    n, spans = tuple(w.numbers), tuple(w.spans)
    return Layout(len(data), tuple(w.checks), n, tuple(w.offsets), tuple(w.texts), spans, tuple(w.lengths), w.little)


@dataclass
class Columns:
    """The fields of some messages of one topic: ``numbers`` and ``texts`` by name, one row per message."""

    times_ns: np.ndarray
    numbers: dict[str, np.ndarray] = field(default_factory=dict)
    texts: dict[str, np.ndarray] = field(default_factory=dict)
    """Arrays of ``str`` (object)."""
    picked: frozenset[str] = frozenset()
    """Numbers read only because a path names them (not part of the topic's own fields)."""

    def __len__(self) -> int:
        return len(self.times_ns)

    def rows(self, rows: np.ndarray | slice) -> Columns:
        return Columns(
            self.times_ns[rows],
            {k: v[rows] for k, v in self.numbers.items()},
            {k: v[rows] for k, v in self.texts.items()},
            self.picked,
        )


def matching(layout: Layout, buf: np.ndarray, starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Which messages (``buf[starts[i] : starts[i] + lengths[i]]``) have ``layout`` (a bool mask)."""
    ok: np.ndarray = (lengths == layout.size) & (buf[starts] == 0) & (buf[starts + 1] == int(layout.little))
    if not ok.any() or not layout.checks:
        return ok
    where = np.flatnonzero(ok)
    positions = np.array([p for p, _ in layout.checks], dtype=np.int64)
    values = np.array([v for _, v in layout.checks], dtype=np.uint32)
    found = buf[starts[where, None, None] + positions[None, :, None] + np.arange(4)].view(
        "<u4" if layout.little else ">u4"
    )[..., 0]
    ok[where] = (found == values).all(axis=1)
    return ok


def gather(buf: np.ndarray, at: np.ndarray, dtype: str, count: int | None) -> np.ndarray:
    """``count`` (None: one, as a 1-D result) values of ``dtype`` at the byte offsets ``at`` of ``buf``: (n, count)."""
    width = np.dtype(dtype).itemsize * (1 if count is None else count)
    raw = buf[at[:, None] + np.arange(width)]
    values: np.ndarray = raw.view(dtype) if dtype != "?" else raw != 0
    if dtype[0] == ">":
        values = values.astype(dtype.replace(">", "<"))  # native for Arrow
    return values[:, 0] if count is None else values


@dataclass
class Problems:
    """What was wrong with a topic's messages, counted (said once, at the end)."""

    unfit: dict[str, int] = field(default_factory=dict)
    nonfinite: int = 0
    not_utf8: int = 0

    def add(self, why: str) -> None:
        self.unfit[why] = self.unfit.get(why, 0) + 1

    def lines(self, *, nonfinite: bool = True) -> list[str]:
        kinds = sorted(self.unfit.items(), key=lambda kv: -kv[1])
        out = [f"{n} message{'s' * (n != 1)} skipped: {why}" for why, n in kinds[:3]]
        if len(kinds) > 3:
            n = sum(n for _, n in kinds[3:])
            out.append(f"{n} more skipped for {len(kinds) - 3} other reasons")
        if self.nonfinite and nonfinite:
            out.append(f"{self.nonfinite} message{'s' * (self.nonfinite != 1)} with NaN or infinity in a field")
        if self.not_utf8:
            out.append(f"{self.not_utf8} string{'s' * (self.not_utf8 != 1)} not UTF-8 (shown with U+FFFD)")
        return out


def read_columns(
    buf: np.ndarray,
    starts: np.ndarray,
    times_ns: np.ndarray,
    layouts: Sequence[Layout],
    problems: Problems,
    wanted: frozenset[str] | None = None,
) -> Columns:
    """The fields of messages at ``starts`` whose layouts ``layouts[i]`` all share :attr:`Layout.names` (one layout:
    every message's); only the ``wanted`` names (None: all)."""
    first = layouts[0]
    same = len(layouts) == 1
    out = Columns(times_ns, picked=frozenset(n.name for n in first.numbers if n.picked))
    bad = np.zeros(len(starts), dtype=bool)
    for j, number in enumerate(first.numbers):
        at = starts + (first.offsets[j] if same else np.array([x.offsets[j] for x in layouts]))
        if number.summary:
            _summary(out, buf, at, number, layouts if not same else None, j, wanted)
            continue
        whole = number.count is None or number.picked  # one column (a slice's: rows of ``count`` items)
        names = [number.name] if whole else [f"{number.name}[{i}]" for i in range(number.count or 0)]
        if not names or (wanted is not None and not wanted.intersection(names)):
            continue
        values = gather(buf, at, number.dtype, number.count)
        if values.dtype.kind == "f":
            bad |= ~np.isfinite(values).reshape(len(starts), -1).all(axis=1)
        for i, name in enumerate(names):
            if wanted is None or name in wanted:
                out.numbers[name] = values if whole else values[:, i]
    for j, name in enumerate(first.texts):
        if wanted is None or name in wanted:
            out.texts[name] = _texts(buf, starts, [x.text_spans[j] for x in layouts], problems)
    for j, (name, _) in enumerate(first.lengths):
        if wanted is None or name in wanted:
            counts = [x.lengths[j][1] for x in layouts]
            out.numbers[name] = np.array(counts * (len(starts) if same else 1), dtype=np.int64)
    problems.nonfinite += int(bad.sum())
    return out


def _summary(
    out: Columns,
    buf: np.ndarray,
    at: np.ndarray,
    number: Number,
    layouts: Sequence[Layout] | None,
    j: int,
    wanted: frozenset[str] | None,
) -> None:
    names = [f"{number.name}.{k}" for k in ("len", "min", "max")]
    if wanted is not None and not wanted.intersection(names):
        return
    counts = np.array([x.numbers[j].count or 0 for x in layouts]) if layouts else np.full(len(at), number.count or 0)
    low = np.full(len(at), np.nan)
    high = np.full(len(at), np.nan)
    if layouts is None and number.count:
        values = gather(buf, at, number.dtype, number.count).astype(np.float64)
        with np.errstate(all="ignore"):
            low, high = np.nanmin(values, axis=1), np.nanmax(values, axis=1)
    else:
        size = np.dtype(number.dtype).itemsize
        for i, (a, c) in enumerate(zip(at, counts, strict=True)):
            if c:
                values = buf[int(a) : int(a) + size * int(c)].view(number.dtype).astype(np.float64)
                low[i], high[i] = np.nanmin(values), np.nanmax(values)
    out.numbers[names[0]] = counts.astype(np.int64)
    out.numbers[names[1]], out.numbers[names[2]] = low, high


def _texts(buf: np.ndarray, starts: np.ndarray, spans: list[tuple[int, int]], problems: Problems) -> np.ndarray:
    """Strings at ``starts + offset`` (one span per message), decoded once per distinct value."""
    offsets = np.array([s[0] for s in spans], dtype=np.int64)
    sizes = np.array([s[1] for s in spans], dtype=np.int64)
    if len(spans) == 1:
        offsets, sizes = np.full(len(starts), offsets[0]), np.full(len(starts), sizes[0])
    if len(sizes) and (sizes == sizes[0]).all():
        width = int(sizes[0])
        if width == 0:
            return np.full(len(starts), "", dtype=object)
        raw = np.ascontiguousarray(buf[(starts + offsets)[:, None] + np.arange(width)]).view(f"S{width}")[:, 0]
    else:  # strings of several lengths: one by one, each distinct value decoded once
        memo: dict[bytes, str] = {}
        out = np.empty(len(starts), dtype=object)
        for i, (s, o, n) in enumerate(zip(starts, offsets, sizes, strict=True)):
            raw_bytes = buf[s + o : s + o + n].tobytes()
            text = memo.get(raw_bytes)
            if text is None:
                text = memo[raw_bytes] = _decoded(raw_bytes, problems)
            elif "\ufffd" in text and raw_bytes.find(b"\xef\xbf\xbd") < 0:
                problems.not_utf8 += 1
            out[i] = text
        return out
    distinct, index = np.unique(raw, return_inverse=True)
    decoded = np.empty(len(distinct), dtype=object)
    for k, value in enumerate(distinct):
        before = problems.not_utf8
        decoded[k] = _decoded(bytes(value), problems)
        if problems.not_utf8 > before:
            problems.not_utf8 += int((index == k).sum()) - 1
    return np.asarray(decoded[index], dtype=object)


def _decoded(raw: bytes, problems: Problems) -> str:
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        problems.not_utf8 += 1
        return raw.decode("utf-8", errors="replace")
