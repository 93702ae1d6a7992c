"""A TF tree as ``view_frames`` and ``tf2_monitor`` see it: every edge with its rate (the average over the record:
messages − 1 over the span between its first and last message), its largest gap, and the problems tf2 users know,
each named once with its frame. Vectorised over the ``/tf`` rows (one sort by edge and time); the walks over the
tree are over frames, not rows. Pure numpy; no rerun import."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import I64
from r2d2_viz.msgs.geometry import frame_of
from r2d2_viz.sources.system.frame_codes import frame_codes

STALE_PERIODS = 5.0
"""A dynamic edge whose last message came more than this many of its periods before the end is stale…"""
STALE_MIN_S = 0.5
"""…and more than this many seconds (a 1 kHz edge is not stale 5 ms before the end)."""
OLDER_PERIODS = 2.0
"""A message stamped more than this many periods of a transform it needs after the newest such transform received
by then is one that "uses a transform older than itself" (tf2: extrapolation into the future)…"""
OLDER_MIN_S = 0.05
"""…and more than this many seconds after it; the frame is named when at least :data:`OLDER_SHARE` of the messages
that name it are such (one late message in hundreds is jitter, not a publisher stamping its transforms late)."""
OLDER_SHARE = 0.1
NS = 1e9


@dataclass(frozen=True)
class TfRows:
    """Dynamic transforms (``/tf``), one row each: parent and child frames (str arrays, as tf2 keys them), when it
    was received and its header stamp (ns)."""

    parents: npt.NDArray[np.object_]
    children: npt.NDArray[np.object_]
    receive_ns: I64
    stamps_ns: I64

    def __len__(self) -> int:
        return len(self.receive_ns)


@dataclass(frozen=True)
class HeaderRows:
    """Messages that name a frame in their ``header`` (not ``/tf``'s): topic ``topics[topic_index[i]]``, frame
    ``frames[i]``, header stamp and receive time (ns)."""

    topics: tuple[str, ...]
    topic_index: npt.NDArray[np.int32]
    frames: npt.NDArray[np.object_]
    stamps_ns: I64
    receive_ns: I64


NO_HEADERS = HeaderRows((), np.zeros(0, np.int32), np.zeros(0, object), np.zeros(0, np.int64), np.zeros(0, np.int64))
NO_TF = TfRows(np.zeros(0, object), np.zeros(0, object), np.zeros(0, np.int64), np.zeros(0, np.int64))


@dataclass(frozen=True)
class Edge:
    """One parent → child edge: ``static`` (``/tf_static``) or its ``count`` messages on ``/tf`` received from
    ``first_ns`` to ``last_ns``, their average ``rate_hz`` (None under two messages) and ``max_gap_s``."""

    parent: str
    child: str
    static: bool
    count: int = 0
    first_ns: int = 0
    last_ns: int = 0
    rate_hz: float | None = None
    max_gap_s: float | None = None


@dataclass(frozen=True)
class TfTree:
    """The edges (by parent, child), the roots (the main tree's first), the problems (one line each) and the
    record's ``(start, end)`` receive times (ns)."""

    edges: tuple[Edge, ...]
    roots: tuple[str, ...]
    problems: tuple[str, ...]
    span_ns: tuple[int, int]
    problem_frames: frozenset[str] = frozenset()

    @property
    def frames(self) -> tuple[str, ...]:
        return tuple(sorted({f for e in self.edges for f in (e.parent, e.child)}))

    def children_of(self, parent: str) -> list[Edge]:
        return [e for e in self.edges if e.parent == parent]


def tf_rows(parents: Iterable[str], children: Iterable[str], receive_ns: I64, stamps_ns: I64) -> TfRows:
    """:class:`TfRows` from frame names as messages carry them (one leading '/' dropped, as tf2 does)."""
    p = np.array([frame_of(f) for f in parents], dtype=object)
    c = np.array([frame_of(f) for f in children], dtype=object)
    return TfRows(p, c, np.asarray(receive_ns, np.int64), np.asarray(stamps_ns, np.int64))


def edge_stats(rows: TfRows) -> list[Edge]:
    """Every dynamic edge with its count, first and last receive time, rate and largest gap: one sort of the rows
    by (edge, receive time), then reductions over each edge's run."""
    n = len(rows)
    if n == 0:
        return []
    names, inverse = frame_codes(np.concatenate([rows.parents, rows.children]))
    code = inverse[:n].astype(np.int64) * len(names) + inverse[n:]
    order = np.lexsort((rows.receive_ns, code))
    code_s, t_s = code[order], rows.receive_ns[order]
    starts = np.flatnonzero(np.r_[True, code_s[1:] != code_s[:-1]])
    counts = np.diff(np.r_[starts, n])
    first, last = t_s[starts], t_s[starts + counts - 1]
    gaps = np.r_[0, np.diff(t_s)]
    gaps[starts] = 0
    max_gap = np.maximum.reduceat(gaps, starts)
    span = (last - first).astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        rate = np.where((counts > 1) & (span > 0), (counts - 1) / span * NS, np.nan)
    out = []
    for k, s in enumerate(starts):
        p, c = divmod(int(code_s[s]), len(names))
        out.append(
            Edge(
                str(names[p]),
                str(names[c]),
                False,
                int(counts[k]),
                int(first[k]),
                int(last[k]),
                None if np.isnan(rate[k]) else float(rate[k]),
                None if counts[k] < 2 else float(max_gap[k]) / NS,
            )
        )
    return out


def analyse(
    dynamic: TfRows,
    static_edges: Iterable[tuple[str, str]],
    headers: HeaderRows = NO_HEADERS,
    *,
    span_ns: tuple[int, int] | None = None,
    end_word: str = "the end of the bag",
) -> TfTree:
    """The tree of ``dynamic`` rows and ``static_edges`` (``/tf_static``'s; an edge on both counts as dynamic), its
    problems, and the frames ``headers`` name checked against it. ``span_ns``: the record's first and last receive
    time (default: the rows')."""
    edges = edge_stats(dynamic)
    moving = {(e.parent, e.child) for e in edges}
    statics = sorted({(frame_of(p), frame_of(c)) for p, c in static_edges} - moving)
    edges += [Edge(p, c, True) for p, c in statics]
    edges.sort(key=lambda e: (e.parent, e.child))
    if span_ns is None:
        times = np.r_[dynamic.receive_ns, headers.receive_ns]
        span_ns = (int(times.min()), int(times.max())) if len(times) else (0, 0)
    parents: dict[str, list[Edge]] = {}
    for e in edges:
        parents.setdefault(e.child, []).append(e)
    problems: list[tuple[str, str]] = []
    for child, its in sorted(parents.items()):
        if len(its) > 1:
            names = sorted({e.parent for e in its})
            problems.append((child, f"{len(names)} parents, {' and '.join(names)} (tf2 keeps whichever came last)"))
    up = {child: max(its, key=lambda e: (e.count, e.static)).parent for child, its in parents.items()}
    problems += _loops(up)
    roots = _roots(edges, up)
    if len(roots) > 1:
        sizes = {r: len(_below(r, edges)) for r in roots}
        roots = sorted(roots, key=lambda r: (-sizes[r], r))
        for r in roots[1:]:
            problems.append((r, f"a second root: its tree of {sizes[r]} frames is not connected to {roots[0]}'s"))
    problems += _stale(edges, span_ns[1], end_word)
    problems += _unreached(headers, up, {f for e in edges for f in (e.parent, e.child)})
    problems += _older(headers, dynamic, edges, up)
    seen: set[tuple[str, str]] = set()
    lines = []
    for frame, text in problems:
        if (frame, text) not in seen:
            seen.add((frame, text))
            lines.append(f"frame {frame}: {text}")
    return TfTree(tuple(edges), tuple(roots), tuple(lines), span_ns, frozenset(f for f, _ in problems))


def chain(frame: str, up: dict[str, str]) -> list[tuple[str, str]]:
    """The ``(parent, child)`` edges from ``frame`` up to its root (stops at a loop)."""
    out, seen = [], {frame}
    while frame in up and up[frame] not in seen:
        out.append((up[frame], frame))
        frame = up[frame]
        seen.add(frame)
    return out


def _loops(up: dict[str, str]) -> list[tuple[str, str]]:
    """Each loop of child → parent links once, named by its first frame (sorted)."""
    found: list[tuple[str, str]] = []
    done: set[str] = set()
    for start in sorted(up):
        path: list[str] = []
        frame: str | None = start
        while frame is not None and frame not in done and frame not in path:
            path.append(frame)
            frame = up.get(frame)
        if frame is not None and frame in path:
            loop = path[path.index(frame) :]
            first = min(loop)
            k = loop.index(first)
            ring = [*loop[k:], *loop[:k], first]
            found.append((first, "in a loop: " + " → ".join(ring) + " (each the parent of the one before)"))
        done.update(path)
    return found


def _roots(edges: list[Edge], up: dict[str, str]) -> list[str]:
    """Frames that are some edge's parent and no edge's child (a tree all in a loop has none)."""
    return sorted({e.parent for e in edges} - set(up))


def _below(root: str, edges: list[Edge]) -> set[str]:
    kids: dict[str, list[str]] = {}
    for e in edges:
        kids.setdefault(e.parent, []).append(e.child)
    out, todo = {root}, [root]
    while todo:
        for k in kids.get(todo.pop(), []):
            if k not in out:
                out.add(k)
                todo.append(k)
    return out


def period_s(edge: Edge) -> float | None:
    return None if edge.rate_hz is None else 1.0 / edge.rate_hz


def _stale(edges: list[Edge], end_ns: int, end_word: str) -> list[tuple[str, str]]:
    out = []
    for e in edges:
        period = period_s(e)
        if e.static or period is None:
            continue
        behind = (end_ns - e.last_ns) / NS
        if behind > max(STALE_PERIODS * period, STALE_MIN_S):
            out.append(
                (
                    e.child,
                    f"stale: its transform from {e.parent} stopped {behind:.3g} s before {end_word} "
                    f"({behind / period:.0f} periods of its {e.rate_hz:.3g} Hz)",
                )
            )
    return out


def _unreached(headers: HeaderRows, up: dict[str, str], frames: set[str]) -> list[tuple[str, str]]:
    out: list[tuple[str, str]] = []
    if not len(headers.frames) or not frames:  # no transforms at all: every message is in the one fixed frame
        return out
    names, inverse = frame_codes(headers.frames)
    for k, name in enumerate(names):
        if not name or name in frames:
            continue
        topics = sorted({headers.topics[i] for i in np.unique(headers.topic_index[inverse == k])})
        out.append((str(name), f"named in the headers of {', '.join(topics)}; no transform reaches it"))
    return out


def _older(headers: HeaderRows, dynamic: TfRows, edges: list[Edge], up: dict[str, str]) -> list[tuple[str, str]]:
    """Header frames whose messages are stamped later than the newest transform of some dynamic edge on their
    chain that was received by the time they were (beyond :data:`OLDER_PERIODS` and :data:`OLDER_MIN_S`)."""
    if not len(headers.frames) or not len(dynamic):
        return []
    by_edge = {(e.parent, e.child): e for e in edges if not e.static and e.rate_hz is not None}
    n = len(dynamic)
    frames, inverse_rows = frame_codes(np.concatenate([dynamic.parents, dynamic.children]))
    code = inverse_rows[:n].astype(np.int64) * len(frames) + inverse_rows[n:]
    index = {str(f): i for i, f in enumerate(frames)}
    held: dict[tuple[str, str], tuple[I64, I64]] = {}
    out = []
    names, inverse = frame_codes(headers.frames)
    for k, name in enumerate(names):
        links = [by_edge[link] for link in chain(str(name), up) if link in by_edge]
        if not links:
            continue
        rows = np.flatnonzero(inverse == k)
        receive, stamp = headers.receive_ns[rows], headers.stamps_ns[rows]
        worst: tuple[float, Edge | None, int] = (0.0, None, 0)
        for e in links:
            if (e.parent, e.child) not in held:
                mine = np.flatnonzero(code == index[e.parent] * len(frames) + index[e.child])
                order = np.argsort(dynamic.receive_ns[mine], kind="stable")
                newest = np.maximum.accumulate(dynamic.stamps_ns[mine][order])
                held[e.parent, e.child] = (dynamic.receive_ns[mine][order], newest)
            got, newest = held[e.parent, e.child]
            at = np.searchsorted(got, receive, side="right") - 1
            known = at >= 0
            lag = (stamp[known] - newest[at[known]]) / NS
            period = period_s(e) or 0.0
            late = lag > max(OLDER_PERIODS * period, OLDER_MIN_S)
            if late.sum() >= OLDER_SHARE * len(rows) and float(lag.max()) > worst[0]:
                worst = (float(lag.max()), e, int(late.sum()))
        if worst[1] is not None:
            topics = sorted({headers.topics[i] for i in np.unique(headers.topic_index[rows])})
            out.append(
                (
                    str(name),
                    f"transforms older than the messages that use it: {', '.join(topics)} stamped up to "
                    f"{worst[0]:.3g} s after the newest {worst[1].parent} → {worst[1].child} transform received by "
                    f"then ({worst[2]} of {len(rows)} messages)",
                )
            )
    return out
