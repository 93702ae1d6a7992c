"""Other topics' fields into the recording, in time order as far as a replay has got (as :class:`TfFeed` does).

Every field of a topic no display draws goes to ``/topics/<topic>`` (``/topics/panda_arm_controller/state``), one
component per field named as ``ros2 topic echo`` names it (``error.positions[0]``), archetype the message type:
numbers as numbers (drag one into a time-series view to plot it), text as text; the selection panel shows the
latest message at the time cursor. Each ``--plot`` path is a ``Scalars`` series under ``/plot/<n>/`` (``n``: the
``--plot`` flag it came with, one time-series view each), named as the path.

Rows go to Rerun as columns, a ``send_columns`` per entity for many messages at once: a live run's as they fall
due, a batch run's (``gather``) held until an entity has :data:`CHUNK_ROWS` of them — a block's few hundred rows
a send cost Rerun more to encode and write than the values themselves.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.errors import SHOWN, listed
from r2d2_viz.msgs.generic.decoder import FieldDecoder
from r2d2_viz.msgs.generic.fields import Columns
from r2d2_viz.msgs.generic.message_path import MessagePath
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.sources.base import Clock
from r2d2_viz.sources.fields_pass import FieldsPass, TopicColumns, plot_paths
from r2d2_viz.sources.plan import RunPlan
from r2d2_viz.viewer.columns import Encoded, send, time_array
from r2d2_viz.viewer.entities import TIMELINE, path

TOPICS = "/topics"
PLOT = "/plot"
CHUNK_ROWS = 4096
"""A batch run sends an entity's rows when it holds this many (Rerun's chunk store keeps sorted chunks of up to
4,096 rows whole)…"""
CHUNK_BYTES = 1 << 20
"""…or this many bytes of values and offsets (Rerun writes a chunk of more than about 1.2–1.4 MB to a file as it is,
not compressed: a script's chunks of zeros, 12,000 rows of 19 fields for 20 entities, made 3.9 MB at 5,000 rows a
chunk, 21 MB at 6,000)."""
HELD_BYTES = 16 << 20
"""All entities together hold at most about this much (a bag of hundreds of slow topics): past it, all are sent."""


def topic_entity(topic: str) -> str:
    """Where a topic's fields go: ``/topics/<topic>``."""
    return path("topics", *topic.strip("/").split("/"))


def plot_view(view: int) -> str:
    return f"{PLOT}/{view}"


def plot_entity(view: int, text: str) -> str:
    """Where the series of the ``--plot`` path ``text`` goes (of the ``view``-th ``--plot`` flag)."""
    return path("plot", str(view), text)


class FieldsFeed:
    """``shown``: topic → type of the topics whose fields are logged; ``plots``: per ``--plot`` flag, its paths;
    ``header_time``: rows at their ``header.stamp`` where the message has one."""

    def __init__(
        self,
        rec: rr.RecordingStream,
        *,
        clock: Clock,
        shown: dict[str, str],
        plots: Sequence[Sequence[MessagePath]] = (),
        header_time: bool = False,
        gather: bool = False,
    ) -> None:
        self.rec, self.clock, self.shown, self.header_time, self.gather = rec, clock, shown, header_time, gather
        self.plots: dict[str, list[tuple[MessagePath, str]]] = {}
        """topic → (path, entity) of each series."""
        for view, paths in enumerate(plots):
            for p in paths:
                entity = plot_entity(view, p.text)
                self.plots.setdefault(p.topic, []).append((p, entity))
                rec.log(entity, rr.SeriesLines(names=p.text), static=True)
        self._pending: deque[TopicColumns] = deque()
        self.messages = 0
        self.plotted: dict[str, int] = {}
        self.known: dict[str, dict[str, pa.DataType]] = {}
        """topic → every field its messages have had so far (what a row lacks is logged empty: cleared)."""
        self._held: dict[str, _Held] = {}
        """entity → its rows not sent yet."""
        self.held_bytes = 0
        """Their bytes, all entities together."""

    def push(self, fields: Sequence[TopicColumns]) -> None:
        for topic, columns in fields:
            if self.header_time and "header.stamp.sec" in columns.numbers:
                stamps = columns.numbers["header.stamp.sec"].astype(np.int64) * 1_000_000_000
                stamps += columns.numbers["header.stamp.nanosec"].astype(np.int64)
                columns.times_ns = np.where(stamps != 0, stamps, columns.times_ns)  # unset: received (as displays)
                order = np.argsort(columns.times_ns, kind="stable")
                columns = columns.rows(order)
            if topic in self.shown:
                known = self.known.setdefault(topic, {})
                for name, values in (*columns.numbers.items(), *columns.texts.items()):
                    if name not in known and name not in columns.picked:
                        known[name] = pa.utf8() if values.dtype == object else pa.from_numpy_dtype(values.dtype)
            self._pending.append((topic, columns))

    @property
    def next_time_ns(self) -> int | None:
        return min((int(c.times_ns[0]) for _, c in self._pending), default=None)

    def until(self, time_ns: int | None = None) -> None:
        """Log what is due up to ``time_ns`` (all when None)."""
        keep: deque[TopicColumns] = deque()
        for topic, columns in self._pending:
            stop = len(columns) if time_ns is None else int(np.searchsorted(columns.times_ns, time_ns, side="right"))
            if stop:
                self._log(topic, columns if stop == len(columns) else columns.rows(slice(0, stop)))
            if stop < len(columns):
                keep.append((topic, columns.rows(slice(stop, None))))
        self._pending = keep

    def _times(self, times_ns: np.ndarray) -> rr.TimeColumn:
        if self.clock == "duration":
            return rr.TimeColumn(TIMELINE, duration=times_ns.astype("timedelta64[ns]"))
        return rr.TimeColumn(TIMELINE, timestamp=times_ns.astype("datetime64[ns]"))

    def _log(self, topic: str, columns: Columns) -> None:
        if topic in self.shown:
            kinds = {n: v.dtype.str for n, v in (*columns.numbers.items(), *columns.texts.items())}
            nbytes = sum(v.nbytes + 4 * len(v) for v in columns.numbers.values()) + 20 * len(columns) * len(
                columns.texts
            )
            piece = (columns, len(self.known.get(topic, {})))  # the fields known by now: what it lacks is cleared
            self._hold(topic_entity(topic), piece, len(columns), nbytes, kinds, topic)
            self.messages += len(columns)
        for p, entity in self.plots.get(topic, ()):
            values = columns.numbers.get(p.field)
            if values is None:
                continue
            at = columns.times_ns
            if p.filters:
                keep = np.ones(len(values), dtype=bool)
                for f in p.filters:
                    column = columns.numbers.get(f.field, columns.texts.get(f.field))
                    keep &= f.mask(column) if column is not None else False
                if not keep.any():
                    continue
                values, at = values[keep], at[keep]
            kind = {"": str(values.shape[1:])}  # a slice's rows of one width in a chunk
            self._hold(entity, (at, values), len(values), values.nbytes, kind, None)
            self.plotted[entity] = self.plotted.get(entity, 0) + len(values)

    def _hold(
        self, entity: str, piece: object, rows: int, nbytes: int, kinds: dict[str, str], topic: str | None
    ) -> None:
        """Rows of ``entity`` to send (a piece of ``topic``'s fields, or of a plot's series: None): at once unless
        gathering, else when a chunk's worth is held. Values of another type than those held (a definition that
        changed between a bag's files) start a new chunk."""
        held = self._held.get(entity)
        if held is not None and any(held.kinds.get(n, k) != k for n, k in kinds.items()):
            self._flush(entity)
            held = None
        if held is None:
            held = self._held[entity] = _Held(topic)
        held.pieces.append(piece)
        held.rows, held.nbytes = held.rows + rows, held.nbytes + nbytes
        held.kinds.update(kinds)
        self.held_bytes += nbytes
        if not self.gather or held.rows >= CHUNK_ROWS or held.nbytes >= CHUNK_BYTES:
            self._flush(entity)
        if self.held_bytes > HELD_BYTES:
            for other in list(self._held):
                self._flush(other)

    def _flush(self, entity: str) -> None:
        held = self._held.pop(entity)
        self.held_bytes -= held.nbytes
        if held.topic is None:
            self._plot(entity, held.pieces)
        else:
            self._send(held.topic, held.pieces)

    def _send(self, topic: str, pieces: list[tuple[Columns, int]]) -> None:
        """Rows of ``topic`` as one chunk, in time order: each field a column of lists of one value (a row lacking a
        field known before it: an empty list, cleared; one before it was known: null, nothing)."""
        times = _joined([c.times_ns for c, _ in pieces])
        order = _order(times)
        sizes = [len(c) for c, _ in pieces]
        archetype = self.shown[topic]
        out: Encoded = []
        for k, (name, typ) in enumerate(self.known.get(topic, {}).items()):
            got = [None if name in c.picked else c.numbers.get(name, c.texts.get(name)) for c, _ in pieces]
            cleared = [k < seen and name not in c.numbers and name not in c.texts for c, seen in pieces]
            if any(g is not None for g in got) or any(cleared):
                descriptor = rr.ComponentDescriptor(name).with_builtin_archetype(archetype)
                out.append((descriptor, _lists(got, cleared, sizes, order, typ)))
        at = times if order is None else times[order]
        send(self.rec, topic_entity(topic), TIMELINE, time_array(at, self.clock), out)

    def _plot(self, entity: str, pieces: list[tuple[np.ndarray, np.ndarray]]) -> None:
        times = _joined([t for t, _ in pieces])
        values = _joined([v for _, v in pieces])
        if (order := _order(times)) is not None:
            times, values = times[order], values[order]
        scalars = rr.Scalars.columns(scalars=values.astype(np.float64).ravel())
        if values.ndim == 2:  # a slice ([:]): every item of each message, a line each (Foxglove: a point each)
            scalars = scalars.partition(np.full(len(values), values.shape[1]))
        self.rec.send_columns(entity, indexes=[self._times(times)], columns=scalars)

    def finish(self, report: Callable[[str], None]) -> None:
        """Log what is left; say which ``--plot`` paths matched no message (an index past every array's end)."""
        self.until(None)
        for entity in list(self._held):
            self._flush(entity)
        for topic, series in self.plots.items():
            for p, entity in series:
                if not self.plotted.get(entity):
                    why = " passes its filter" if p.filters else " has it (an index past the array's end?)"
                    report(f"--plot {p.text}: no message of {topic}{why}")


class LiveFields:
    """A live graph's topics no display draws, every field, logged as they arrive (``store``: the graph's types)."""

    def __init__(self, rec: rr.RecordingStream, store: Any, header_time: bool = False) -> None:
        self.feed = FieldsFeed(rec, clock="timestamp", shown={}, header_time=header_time)
        self.store = store
        self.decoders: dict[str, FieldDecoder] = {}

    def log(self, messages: Sequence[TopicMessage]) -> None:
        by_topic: dict[str, list[TopicMessage]] = {}
        for m in messages:
            by_topic.setdefault(m.topic, []).append(m)
        for topic, got in by_topic.items():
            decoder = self.decoders.get(topic)
            if decoder is None or decoder.msgtype != got[0].msgtype:
                decoder = self.decoders[topic] = FieldDecoder(self.store, got[0].msgtype)
                self.feed.shown[topic] = got[0].msgtype
            data = [bytes(m.data) for m in got if m.msgtype == decoder.msgtype]
            lengths = np.array([len(d) for d in data], dtype=np.int64)
            starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
            times = np.array([m.time_ns for m in got if m.msgtype == decoder.msgtype], dtype=np.int64)
            buf = np.frombuffer(b"".join(data), dtype=np.uint8)
            self.feed.push([(topic, c) for c in decoder.decode(buf, starts, lengths, times) if len(c)])
        self.feed.until(None)

    def finish(self, report: Callable[[str], None]) -> None:
        for topic, decoder in self.decoders.items():
            if lines := decoder.problems.lines():
                report(f"{topic}: {'; '.join(lines)}")


@dataclass
class _Held:
    """An entity's rows not sent yet: pieces of ``topic``'s fields (None: a plot's), their rows and bytes, each
    field's dtype."""

    topic: str | None
    pieces: list[Any] = field(default_factory=list)
    rows: int = 0
    nbytes: int = 0
    kinds: dict[str, str] = field(default_factory=dict)


def _joined(parts: list[np.ndarray]) -> np.ndarray:
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def _order(times: np.ndarray) -> np.ndarray | None:
    """The rows in time order (ties in the order logged); None when they already are."""
    if len(times) < 2 or bool((times[1:] >= times[:-1]).all()):
        return None
    return np.argsort(times, kind="stable")


def _values(values: np.ndarray) -> pa.Array:
    return pa.array(values, type=pa.utf8()) if values.dtype == object else pa.array(values)


def _lists(
    got: list[np.ndarray | None], cleared: list[bool], sizes: list[int], order: np.ndarray | None, typ: pa.DataType
) -> pa.Array:
    """One field's column over pieces of ``sizes`` rows: a list of its value a row where a piece has it (``got``),
    an empty list where it is ``cleared``, else null; rows taken in ``order``. Built from buffers: Arrow's
    ``ListArray.from_arrays(mask=)`` would import pyarrow.compute (60 ms)."""
    if all(g is not None for g in got):
        values = _joined([g for g in got if g is not None])
        values = values if order is None else values[order]
        return pa.ListArray.from_arrays(pa.array(np.arange(len(values) + 1, dtype=np.int32)), _values(values))
    n = sum(sizes)
    present = np.repeat(np.array([g is not None for g in got]), sizes)
    valid = present | np.repeat(np.array(cleared), sizes)
    parts = [g for g in got if g is not None]
    if parts and order is not None:
        full = np.empty(n, dtype=parts[0].dtype)
        full[present] = _joined(parts)
        present, valid = present[order], valid[order]
        array = _values(full[order][present])
    else:
        present, valid = (present, valid) if order is None else (present[order], valid[order])
        array = _values(_joined(parts)) if parts else pa.array([], type=typ)
    offsets = np.zeros(n + 1, dtype=np.int32)
    np.cumsum(present, out=offsets[1:])
    validity = None if valid.all() else pa.py_buffer(np.packbits(valid, bitorder="little"))  # LSB first, 1 = valid
    return pa.Array.from_buffers(pa.list_(array.type), n, [validity, pa.py_buffer(offsets)], children=[array])


@dataclass(frozen=True)
class FieldsRun:
    """A bag's other topics' fields: what decodes them in the pass, what logs them."""

    decoding: FieldsPass
    shown: dict[str, str]
    plots: tuple[tuple[MessagePath, ...], ...]
    clock: Clock
    header_time: bool
    gather: bool = False
    """A batch run's: rows sent in chunks of :data:`CHUNK_ROWS` (a live one's as they fall due)."""

    def feed(self, rec: rr.RecordingStream) -> FieldsFeed:
        return FieldsFeed(
            rec, clock=self.clock, shown=self.shown, plots=self.plots, header_time=self.header_time, gather=self.gather
        )


def fields_run(
    plan: RunPlan, plots: Sequence[Sequence[str]], clock: Clock, *, header_time: bool = False, gather: bool = False
) -> FieldsRun | None:
    """The fields a bag's pass decodes: every undisplayed topic's, and the ``--plot`` paths' (checked here, before
    anything is written: a ``BagError`` naming the topic's fields). None: not a bag, or nothing to decode. ``gather``:
    a batch run's (:attr:`FieldsRun.gather`)."""
    if plan.replay is None:
        return None
    bag = plan.replay.bag
    checked = tuple(plot_paths(bag, texts) for texts in plots)
    decoding = FieldsPass(bag, plan.undisplayed, [p for group in checked for p in group], stamps=header_time)
    if not decoding.decoders and not decoding.unusable:
        return None
    shown = {t: m for t, m in plan.undisplayed.items() if t in decoding.decoders}
    return FieldsRun(decoding, shown, checked, clock, header_time, gather)


def undecoded_line(undisplayed: Mapping[str, str], fields: FieldsRun | None) -> str:
    """The topics no display draws and whose fields cannot be decoded, in one line ("": none), with why (each
    reason once)."""
    skipped = dict(undisplayed)
    why: dict[str, list[str]] = {}
    if fields is not None:
        for topic in fields.decoding.topics:
            skipped.pop(topic, None)
        for topic, reason in sorted(fields.decoding.unusable.items()):
            msgtype, _, text = reason.partition(": ")
            if topic in skipped and msgtype not in why.setdefault(text[:100], []):
                why[text[:100]].append(msgtype)
    if not skipped:
        return ""
    n = len(skipped)
    every = " (--list shows every topic)" if n > SHOWN + 1 else ""
    names = listed((t if why else f"{t} ({m})" for t, m in sorted(skipped.items())), first=3)  # reasons name types
    reasons = "; ".join(f"{listed(types, first=2)}: {text}" for text, types in why.items())
    return f"{n} topic{'s' * (n != 1)} that cannot be decoded, not shown: {names}{every}" + (
        f"; {reasons}" if why else ""
    )
