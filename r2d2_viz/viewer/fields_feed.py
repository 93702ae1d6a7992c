"""Other topics' fields into the recording, in time order as far as a replay has got (as :class:`TfFeed` does).

Every field of a topic no display draws goes to ``/topics/<topic>`` (``/topics/panda_arm_controller/state``), one
component per field named as ``ros2 topic echo`` names it (``error.positions[0]``), archetype the message type:
numbers as numbers (drag one into a time-series view to plot it), text as text; the selection panel shows the
latest message at the time cursor. Each ``--plot`` path is a ``Scalars`` series under ``/plot/<n>/`` (``n``: the
``--plot`` flag it came with, one time-series view each), named as the path.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
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
    ) -> None:
        self.rec, self.clock, self.shown, self.header_time = rec, clock, shown, header_time
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

    def _arrow(self, topic: str, columns: Columns) -> Encoded:
        """Each field as an Arrow list array of one value a row, built from the numpy column (Rerun's
        ``DynamicArchetype.columns`` would inspect and partition every column in Python: 3x slower here)."""
        archetype = self.shown[topic]
        offsets = pa.array(np.arange(len(columns) + 1, dtype=np.int32))
        out: Encoded = []
        for name, values in (*columns.numbers.items(), *columns.texts.items()):
            if name in columns.picked:
                continue
            descriptor = rr.ComponentDescriptor(name).with_builtin_archetype(archetype)
            array = pa.array(values, type=pa.utf8()) if values.dtype == object else pa.array(values)
            out.append((descriptor, pa.ListArray.from_arrays(offsets, array)))
        absent = [
            (n, t) for n, t in self.known.get(topic, {}).items() if n not in columns.numbers and n not in columns.texts
        ]
        if absent:  # fields of other messages: empty at these rows (Rerun's latest-at is per field)
            empty = pa.array(np.zeros(len(columns) + 1, dtype=np.int32))
            for name, typ in absent:
                descriptor = rr.ComponentDescriptor(name).with_builtin_archetype(archetype)
                out.append((descriptor, pa.ListArray.from_arrays(empty, pa.array([], type=typ))))
        return out

    def _times(self, times_ns: np.ndarray) -> rr.TimeColumn:
        if self.clock == "duration":
            return rr.TimeColumn(TIMELINE, duration=times_ns.astype("timedelta64[ns]"))
        return rr.TimeColumn(TIMELINE, timestamp=times_ns.astype("datetime64[ns]"))

    def _log(self, topic: str, columns: Columns) -> None:
        times = self._times(columns.times_ns)
        if topic in self.shown:
            send(
                self.rec,
                topic_entity(topic),
                TIMELINE,
                time_array(columns.times_ns, self.clock),
                self._arrow(topic, columns),
            )
            self.messages += len(columns)
        for p, entity in self.plots.get(topic, ()):
            values = columns.numbers.get(p.field)
            if values is None:
                continue
            at = times
            if p.filters:
                keep = np.ones(len(values), dtype=bool)
                for f in p.filters:
                    column = columns.numbers.get(f.field, columns.texts.get(f.field))
                    keep &= f.mask(column) if column is not None else False
                if not keep.any():
                    continue
                values, at = values[keep], self._times(columns.times_ns[keep])
            scalars = rr.Scalars.columns(scalars=values.astype(np.float64).ravel())
            if values.ndim == 2:  # a slice ([:]): every item of each message, a line each (Foxglove: a point each)
                scalars = scalars.partition(np.full(len(values), values.shape[1]))
            self.rec.send_columns(entity, indexes=[at], columns=scalars)
            self.plotted[entity] = self.plotted.get(entity, 0) + len(values)

    def finish(self, report: Callable[[str], None]) -> None:
        """Log what is left; say which ``--plot`` paths matched no message (an index past every array's end)."""
        self.until(None)
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


@dataclass(frozen=True)
class FieldsRun:
    """A bag's other topics' fields: what decodes them in the pass, what logs them."""

    decoding: FieldsPass
    shown: dict[str, str]
    plots: tuple[tuple[MessagePath, ...], ...]
    clock: Clock
    header_time: bool

    def feed(self, rec: rr.RecordingStream) -> FieldsFeed:
        return FieldsFeed(rec, clock=self.clock, shown=self.shown, plots=self.plots, header_time=self.header_time)


def fields_run(
    plan: RunPlan, plots: Sequence[Sequence[str]], clock: Clock, *, header_time: bool = False
) -> FieldsRun | None:
    """The fields a bag's pass decodes: every undisplayed topic's, and the ``--plot`` paths' (checked here, before
    anything is written: a ``BagError`` naming the topic's fields). None: not a bag, or nothing to decode."""
    if plan.replay is None:
        return None
    bag = plan.replay.bag
    checked = tuple(plot_paths(bag, texts) for texts in plots)
    decoding = FieldsPass(bag, plan.undisplayed, [p for group in checked for p in group], stamps=header_time)
    if not decoding.decoders and not decoding.unusable:
        return None
    shown = {t: m for t, m in plan.undisplayed.items() if t in decoding.decoders}
    return FieldsRun(decoding, shown, checked, clock, header_time)


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
