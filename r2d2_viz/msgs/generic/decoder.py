"""One topic's messages, many at a time, as :class:`~r2d2_viz.msgs.generic.fields.Columns`: the layouts met before are
tried first (numpy comparisons over all the messages), a message no layout fits is walked and its layout tried on
the rest; when layouts stop paying (each fits only a few messages: strings of every length, as in a log) the rest
are walked one by one and gathered per field. Problems are counted, never raised (:class:`Problems`).

Also which definition a bag's topic is decoded with (:func:`topic_store`). Pure: numpy, rosbags' typestore.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from r2d2_viz.msgs.generic.fields import Columns, Layout, Problems, matching, read_columns, walk
from r2d2_viz.msgs.typestore import MsgError, typestore

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

SEQ = "header.seq"
"""ROS 1's header field that the conversion to CDR drops; given beside the messages (:attr:`Block.seq`)."""
KEPT_LAYOUTS = 8
"""Layouts remembered per topic (tried first on the next messages)."""
MIN_MATCHED = 4
"""A new layout that fits fewer messages than this ends the numpy matching for the rest of the window."""


def topic_store(msgtype: str, definition: str, encoding: str, *, humble: bool = False) -> Typestore:
    """The typestore a bag's topic is decoded with: its own definition where the bag carries one (and its messages
    are not converted to Humble's layout: ``humble``), else Humble's. ``MsgError`` when neither defines it."""
    if definition and not humble:
        from r2d2_viz.msgs.definitions import own_store

        return own_store(msgtype, definition, encoding)
    store = typestore()
    if msgtype not in store.fielddefs:
        raise MsgError(f"{msgtype}: no definition in the bag, not a Humble type")
    return store


class FieldDecoder:
    """Decodes one topic's messages of ``msgtype`` (defined in ``store``); ``wanted``: only these field names (None:
    all); ``keep``: names read whatever the summary (the items ``--plot`` paths name); ``ros1``: ``store`` holds a ROS 1
    definition (its ``byte`` is signed)."""

    def __init__(
        self,
        store: Typestore,
        msgtype: str,
        wanted: frozenset[str] | None = None,
        keep: frozenset[str] = frozenset(),
        *,
        ros1: bool = False,
    ) -> None:
        self.store, self.msgtype, self.wanted, self.ros1 = store, msgtype, wanted, ros1
        self.keep = keep | (wanted or frozenset())
        self.layouts: list[Layout] = []
        self.problems = Problems()
        self.decoded = 0

    def decode(
        self,
        buf: np.ndarray,
        starts: np.ndarray,
        lengths: np.ndarray,
        times_ns: np.ndarray,
        seq: np.ndarray | None = None,
    ) -> list[Columns]:
        """The fields of the messages ``buf[starts[i] : starts[i] + lengths[i]]`` received at ``times_ns`` (in
        order), as columns: one per group of messages sharing their field names, rows in time order. ``seq``: their
        ROS 1 ``header.seq`` (-1: none), a field first where every message has one."""
        left = np.ones(len(starts), dtype=bool)
        order = np.argsort(lengths, kind="stable")  # a layout has one size: its candidates are one run of these
        sorted_lengths = lengths[order]
        groups: list[tuple[np.ndarray, list[Layout]]] = []

        def fit(layout: Layout) -> np.ndarray:
            """The rows not taken yet that have ``layout``."""
            lo, hi = np.searchsorted(sorted_lengths, [layout.size, layout.size + 1])
            rows = order[lo:hi]
            rows = rows[left[rows]]
            found: np.ndarray = rows[matching(layout, buf, starts[rows], lengths[rows])]
            return found

        for layout in list(self.layouts):
            if not left.any():
                break
            if len(rows := fit(layout)):
                groups.append((np.sort(rows), [layout]))
                left[rows] = False
        while left.any():
            i = int(np.argmax(left))
            found = self._walk(buf, int(starts[i]), int(lengths[i]))
            if found is None:
                left[i] = False
                continue
            rows = np.union1d(fit(found), [i])
            left[rows] = False
            groups.append((rows, [found]))
            self.layouts = [found, *self.layouts[: KEPT_LAYOUTS - 1]]
            if len(rows) < MIN_MATCHED:
                break
        groups += self._one_by_one(buf, starts, lengths, np.flatnonzero(left))
        if seq is None or (self.wanted is not None and SEQ not in self.keep) or not bool(np.all(seq >= 0)):
            seq = None
        return self._columns(buf, starts, times_ns, groups, seq)

    def _walk(self, buf: np.ndarray, start: int, length: int) -> Layout | None:
        try:
            return walk(
                self.store, self.msgtype, memoryview(buf[start : start + length].tobytes()), self.keep, ros1=self.ros1
            )
        except ValueError as exc:
            self.problems.add(str(exc))
            return None

    def _one_by_one(
        self, buf: np.ndarray, starts: np.ndarray, lengths: np.ndarray, rows: np.ndarray
    ) -> list[tuple[np.ndarray, list[Layout]]]:
        """Messages walked one by one, grouped by their field names."""
        by_names: dict[object, tuple[list[int], list[Layout]]] = {}
        for i in rows:
            layout = self._walk(buf, int(starts[i]), int(lengths[i]))
            if layout is not None:
                found = by_names.setdefault(layout.names, ([], []))
                found[0].append(int(i))
                found[1].append(layout)
        return [(np.array(r, dtype=np.int64), ls) for r, ls in by_names.values()]

    def _columns(
        self,
        buf: np.ndarray,
        starts: np.ndarray,
        times_ns: np.ndarray,
        groups: list[tuple[np.ndarray, list[Layout]]],
        seq: np.ndarray | None,
    ) -> list[Columns]:
        """Groups of one layout each (or of several, one per message) merged where their names agree."""
        merged: dict[object, list[tuple[np.ndarray, list[Layout]]]] = {}
        for rows, layouts in groups:
            merged.setdefault(layouts[0].names, []).append((rows, layouts))
        out: list[Columns] = []
        for parts in merged.values():
            columns = []
            for rows, layouts in parts:
                got = read_columns(buf, starts[rows], times_ns[rows], layouts, self.problems, self.wanted)
                if seq is not None:
                    got.numbers = {SEQ: seq[rows].astype(np.uint32), **got.numbers}
                columns.append(got)
                self.decoded += len(rows)
            out.append(_joined(columns))
        return out


def _joined(parts: list[Columns]) -> Columns:
    """Columns of the same names as one, in time order."""
    if len(parts) == 1:
        return parts[0]
    times = np.concatenate([p.times_ns for p in parts])
    order = np.argsort(times, kind="stable")
    first = parts[0]
    return Columns(
        times[order],
        {k: np.concatenate([p.numbers[k] for p in parts])[order] for k in first.numbers},
        {k: np.concatenate([p.texts[k] for p in parts])[order] for k in first.texts},
        first.picked,
    )
