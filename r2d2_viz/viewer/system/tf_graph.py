"""The TF tree as a graph in the recording (``--tf-tree`` with a sink): ``/tf_tree`` holds Rerun ``GraphNodes`` (a
node per frame, named by it, laid out as rqt_tf_tree draws: depth across, siblings down) and ``GraphEdges``
(parent → child), one snapshot every :data:`PERIOD_NS` of record time, so the node labels — each frame's rate over
the last :data:`WINDOW_NS` and its age (time since its transform last came) — change under the time cursor. Stale
frames are red (:data:`~r2d2_viz.sources.system.tf_tree.STALE_PERIODS`), static ones grey, the roots blue; an edge on
both ``/tf_static`` and ``/tf`` is dynamic from its first ``/tf`` message on, as the printed tree counts it.

Fed by :class:`~r2d2_viz.viewer.tf_recorded.RecordedTf` with every transform row as it is logged (batch or live);
per feed, numpy over the rows (one ``bincount`` and one ``maximum.at`` per snapshot)."""

from __future__ import annotations

import numpy as np
import rerun as rr

from r2d2_viz.arrays import I64
from r2d2_viz.sources.base import Clock, TfRecords
from r2d2_viz.sources.system.frame_codes import frame_codes
from r2d2_viz.sources.system.tf_tree import STALE_MIN_S, STALE_PERIODS
from r2d2_viz.sources.system.time_base import RECEIVE, TimeBase
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.columns import encoded, send, time_array

ENTITY = "/tf_tree"
PERIOD_NS = 500_000_000
"""A snapshot of the graph every half second of record time."""
WINDOW_NS = 2_000_000_000
"""Rates over the last 2 s (tf2_monitor's sliding average)."""
NEVER = np.iinfo(np.int64).min
STATIC_COLOR, FRESH_COLOR, STALE_COLOR, ROOT_COLOR = 0x90A4AEFF, 0x43A047FF, 0xE53935FF, 0x1E88E5FF
SPACING = (190.0, 48.0)
"""Node spacing across (depth) and down (siblings), in the view's own units."""
LEAF_ROWS = 12


class TfGraph:
    """Logs the TF graph's snapshots as transforms arrive (:meth:`add`, in time order per kind)."""

    def __init__(
        self,
        rec: rr.RecordingStream,
        *,
        clock: Clock,
        timeline: str = entities.TIMELINE,
        period_ns: int = PERIOD_NS,
        window_ns: int = WINDOW_NS,
        time_base: TimeBase = RECEIVE,
        horizon_ns: int | None = None,
    ) -> None:
        self.rec, self.clock, self.timeline = rec, clock, timeline
        self.period_ns, self.window_ns = period_ns, window_ns
        self.time_base, self.horizon_ns = time_base, horizon_ns
        """Receive times (of ``/tf_static``, of :meth:`advance`) → the run's; :meth:`advance` fills at most this far
        past the newest transform (a run's clock and its transforms' that disagree fill nothing)."""
        self.edges: list[tuple[str, str]] = []
        self._index: dict[tuple[str, str], int] = {}
        self.static: set[int] = set()
        self._first = np.zeros(0, np.int64)
        self._last = np.zeros(0, np.int64)
        self._count = np.zeros(0, np.int64)
        self._recent = (np.zeros(0, np.int64), np.zeros(0, np.int64))  # codes, times within the window
        self._next: int | None = None
        self.snapshots = 0

    def add(self, records: TfRecords) -> None:
        """Transform rows just logged; snapshots due by their last time are logged."""
        if not len(records):
            return
        codes = self._codes(records.parents, records.children)
        times = np.asarray(records.times_ns, np.int64)
        if records.static:
            self.static |= {int(c) for c in np.unique(codes)}
            self._log_snapshots(np.array([self.time_base.at(int(times.max()))]), codes[:0], times[:0])
            return
        order = np.argsort(times, kind="stable")
        codes, times = codes[order], times[order]
        np.minimum.at(self._first, codes, times)
        start = int(times[0]) if self._next is None else self._next
        due = np.arange(start, int(times[-1]) + 1, self.period_ns, dtype=np.int64)
        if len(due):
            self._log_snapshots(due, codes, times)
            self._next = int(due[-1]) + self.period_ns
        np.maximum.at(self._last, codes, times)
        self._count += np.bincount(codes, minlength=len(self.edges))
        recent_codes, recent_times = (np.r_[a, b] for a, b in zip(self._recent, (codes, times), strict=True))
        keep = recent_times > int(times[-1]) - self.window_ns
        self._recent = (recent_codes[keep], recent_times[keep])

    def advance(self, receive_ns: int) -> None:
        """The run has got to ``receive_ns`` (every transform before it given): the snapshots due by then, so a frame
        whose transforms stopped ages and turns stale while the bag goes on."""
        if self._next is None:
            return  # no moving edge yet: the static graph's one snapshot holds
        upto = self.time_base.at(receive_ns)
        if self.horizon_ns is not None and upto - int(self._last.max()) > self.horizon_ns:
            return
        due = np.arange(self._next, upto + 1, self.period_ns, dtype=np.int64)
        if len(due):
            self._log_snapshots(due, np.zeros(0, np.int64), np.zeros(0, np.int64))
            self._next = int(due[-1]) + self.period_ns

    def _codes(self, parents: tuple[str, ...], children: tuple[str, ...]) -> I64:
        """Each row's edge number (new edges numbered as they come)."""
        above, up = frame_codes(parents)  # not a fixed-width str array: one long name made every cell as long
        below, down = frame_codes(children)
        uniq, inverse = np.unique(up.astype(np.int64) * len(below) + down, return_inverse=True)
        numbers = np.empty(len(uniq), np.int64)
        for k, pair in enumerate(uniq):
            edge = (str(above[pair // len(below)]), str(below[pair % len(below)]))
            if edge not in self._index:
                self._index[edge] = len(self.edges)
                self.edges.append(edge)
            numbers[k] = self._index[edge]
        grow = len(self.edges) - len(self._first)
        if grow:
            self._first = np.r_[self._first, np.full(grow, np.iinfo(np.int64).max)]
            self._last = np.r_[self._last, np.full(grow, NEVER)]
            self._count = np.r_[self._count, np.zeros(grow, np.int64)]
        out: I64 = numbers[inverse.reshape(-1)]
        return out

    def _log_snapshots(self, due: I64, codes: I64, times: I64) -> None:
        """A snapshot at each time of ``due`` from the rows before this feed and ``codes, times`` (this feed's)."""
        frames, positions, roots = _layout(self.edges)
        node = {f: i for i, f in enumerate(frames)}
        child = np.array([node[c] for _, c in self.edges], np.int64)
        all_codes, all_times = np.r_[self._recent[0], codes], np.r_[self._recent[1], times]
        order = np.argsort(all_times, kind="stable")  # a feed may reach back before the last one's end
        all_codes, all_times = all_codes[order], all_times[order]
        labels: list[str] = []
        colors: list[int] = []
        for t in due:
            lo, hi = np.searchsorted(all_times, [t - self.window_ns, t], side="right")
            counts = np.bincount(all_codes[lo:hi], minlength=len(self.edges))
            last = self._last.copy()
            upto = int(np.searchsorted(times, t, side="right"))
            np.maximum.at(last, codes[:upto], times[:upto])
            seen = self._count + np.bincount(codes[:upto], minlength=len(self.edges))
            with np.errstate(divide="ignore", invalid="ignore"):  # the edge's average period so far (the tree's)
                period = np.where(seen > 1, (last - self._first) / (seen - 1) / 1e9, np.nan)
            span = np.minimum(self.window_ns, t - self._first) / 1e9
            partial = t - self.window_ns < self._first  # the edge's first message starts the span
            with np.errstate(divide="ignore", invalid="ignore"):
                rate = np.where(span > 0, (counts - partial) / span, np.nan)
            age = np.where(last == NEVER, np.nan, (t - last) / 1e9)
            text = list(frames)
            color = [ROOT_COLOR if f in roots else STATIC_COLOR for f in frames]
            for e, (_, c) in enumerate(self.edges):
                i = int(child[e])
                if e in self.static and np.isnan(age[e]):  # on /tf too: dynamic from its first message there
                    text[i], color[i] = f"{c}\nstatic", STATIC_COLOR
                elif not np.isnan(age[e]):
                    stale = bool(age[e] > max(STALE_PERIODS * period[e], STALE_MIN_S))  # NaN: one message, never
                    text[i] = f"{c}\n{rate[e]:.3g} Hz · {age[e]:.2g} s"
                    color[i] = STALE_COLOR if stale else FRESH_COLOR
            labels += text
            colors += color
        k = len(due)
        nodes = rr.GraphNodes.columns(
            node_ids=frames * k, labels=labels, colors=np.array(colors, np.uint32), positions=np.tile(positions, (k, 1))
        ).partition([len(frames)] * k)
        links = [*rr.GraphEdges.columns(edges=self.edges * k).partition([len(self.edges)] * k)] if self.edges else []
        kind = rr.GraphEdges.columns(graph_type=["directed"] * k)  # one per snapshot
        shown = rr.GraphNodes.columns(show_labels=[True] * k)  # however many frames (Rerun hides many by default)
        columns = [*nodes, *links, *kind, *shown]
        send(self.rec, ENTITY, self.timeline, time_array(due, self.clock), encoded(columns))
        self.snapshots += k


def _layout(edges: list[tuple[str, str]]) -> tuple[list[str], np.ndarray, set[str]]:
    """The frames (depth-first from each root), their positions and the roots, as rqt_tf_tree draws left to right:
    depth across, subtrees down, and a frame's leaf children in columns of :data:`LEAF_ROWS` (a robot's 40 sensors
    fixed to base_link stay a compact block)."""
    kids: dict[str, list[str]] = {}
    children = {c for _, c in edges}
    for p, c in edges:
        kids.setdefault(p, []).append(c)
    roots = sorted({p for p, _ in edges} - children)
    rest = sorted({f for e in edges for f in e} - set(roots))
    order: list[str] = []
    place: dict[str, tuple[float, float]] = {}
    cursor = 0  # the next free row

    def visit(frame: str, depth: int) -> float:
        nonlocal cursor
        order.append(frame)
        place[frame] = (depth * SPACING[0], 0.0)
        mine = [k for k in sorted(kids.get(frame, [])) if k not in place]
        ys = [visit(k, depth + 1) for k in mine if kids.get(k)]
        leaves = [k for k in mine if not kids.get(k) and k not in place]
        rows = min(len(leaves), LEAF_ROWS)
        for j, leaf in enumerate(leaves):
            order.append(leaf)
            place[leaf] = ((depth + 1 + j // rows) * SPACING[0], (cursor + j % rows) * SPACING[1])
        if leaves:
            ys.append((cursor + (rows - 1) / 2) * SPACING[1])
            cursor += rows
        if not ys:
            ys, cursor = [cursor * SPACING[1]], cursor + 1
        place[frame] = (depth * SPACING[0], (ys[0] + ys[-1]) / 2)
        return place[frame][1]

    for frame in [*roots, *rest]:  # frames in loops: no root reaches them
        if frame not in place:
            visit(frame, 0)
    return order, np.array([place[f] for f in order], np.float32).reshape(-1, 2), set(roots)
