"""What drives a robot: the source protocol, and the chunks of samples every source yields.

A *source* names the joints it drives and yields :class:`SampleChunk` s: the times of its samples (int64
nanoseconds on its clock), the positions of some of the robot's joints, and extra named-frame transforms
(such as ``odom → base_link`` of a driving robot). Generated motions (:mod:`r2d2_viz.sources.motion`) and recorded
ones (bags) are sources; the runner and the stream do not know which one runs.

A chunk may carry a subset of the joints, and a sample may leave a joint out (``NaN``): the joint then
keeps its last value, as robot_state_publisher does (:class:`JointState`). Before its first value a joint
is at 0. A *sample* is a time step; a *frame* is always a TF frame. Pure numpy; no rerun import.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import F64, I64
from r2d2_viz.errors import listed

Clock = Literal["duration", "timestamp"]
"""``duration``: time since the start (generated motions); ``timestamp``: nanoseconds since the Unix epoch."""


@dataclass(frozen=True, eq=False)
class FrameTrack:
    """``T_parent_child`` of one named-frame edge at every sample of a chunk."""

    parent: str
    child: str
    translation: F64  # (n, 3)
    quat_xyzw: F64  # (n, 4)


@dataclass(frozen=True, eq=False)
class SampleChunk:
    """Consecutive samples of a source."""

    times_ns: I64  # (n,) non-decreasing, on the source's clock
    joints: tuple[str, ...]
    """The columns of ``positions``: some of the robot's actuated joints."""
    positions: F64  # (n, len(joints)); NaN: not given in that sample (the joint keeps its last value)
    frames: tuple[FrameTrack, ...] = ()
    """One track per edge of :attr:`Source.frames`, in that order."""

    def __len__(self) -> int:
        return len(self.times_ns)


class Source(Protocol):
    """Anything that yields samples for a robot (see the module docstring)."""

    @property
    def joints(self) -> tuple[str, ...]:
        """The joints this source drives (a subset of the robot's actuated joints)."""
        ...

    @property
    def frames(self) -> tuple[tuple[str, str], ...]:
        """``(parent, child)`` of the extra transforms every chunk carries (:attr:`SampleChunk.frames`)."""
        ...

    @property
    def clock(self) -> Clock: ...

    def chunks(self, max_samples: int) -> Iterator[SampleChunk]:
        """All samples, in chunks of at most ``max_samples``; may never end (live generated motions)."""
        ...


class JointState:
    """The latest value of every actuated joint, across chunks: robot_state_publisher's joint state.

    :meth:`update` turns a chunk (any subset of the joints, NaN for "not given") into full rows ``(n, A)``
    in ``joints`` order, each missing value carried forward from the last one given (0 before any)."""

    def __init__(self, joints: Sequence[str]) -> None:
        self.joints = tuple(joints)
        self._column = {name: i for i, name in enumerate(self.joints)}
        self.last = np.zeros(len(self.joints))

    def columns(self, names: Sequence[str]) -> list[int]:
        """Where each of ``names`` goes in a full row; raises ``KeyError`` naming an unknown joint."""
        try:
            return [self._column[name] for name in names]
        except KeyError as exc:
            raise KeyError(f"no actuated joint {exc.args[0]!r}; actuated joints are {listed(self.joints)}") from None

    def update(self, chunk: SampleChunk) -> F64:
        n = len(chunk)
        if chunk.joints == self.joints:
            rows = np.array(chunk.positions, dtype=np.float64)
        else:
            rows = np.full((n, len(self.joints)), np.nan)
            rows[:, self.columns(chunk.joints)] = chunk.positions
        if n == 0:
            return rows.reshape(0, len(self.joints))
        missing = np.isnan(rows)
        if missing.any():
            rows = _carry_forward(rows, missing, self.last)
        self.last = rows[-1].copy()
        return rows


def _carry_forward(rows: F64, missing: npt.NDArray[np.bool_], last: F64) -> F64:
    """Each NaN replaced by the latest value above it in its column, or by ``last`` (vectorised)."""
    n = len(rows)
    padded = np.vstack([last[None, :], rows])
    index = np.where(np.vstack([np.zeros((1, rows.shape[1]), dtype=bool), missing]), 0, np.arange(n + 1)[:, None])
    np.maximum.accumulate(index, axis=0, out=index)
    filled: F64 = np.take_along_axis(padded, index, axis=0)[1:]
    return filled


def last_per_time(chunk: SampleChunk) -> SampleChunk:
    """Samples that share a time (``times_ns`` non-decreasing) as one: the last, with the joints it leaves out
    (NaN) taken from the samples before it at that time — what applying each in file order leaves. So the robot,
    its transforms and its plots at that time all come from one sample (Rerun would otherwise hold several rows
    at one time, each consumer free to pick its own). Vectorised."""
    t = chunk.times_ns
    if len(t) < 2 or bool(np.all(t[1:] != t[:-1])):
        return chunk
    last = np.flatnonzero(np.append(t[1:] != t[:-1], True))  # the last sample at each time
    first = np.concatenate([[0], last[:-1] + 1])
    given = np.where(np.isnan(chunk.positions), -1, np.arange(len(t))[:, None])
    np.maximum.accumulate(given, axis=0, out=given)
    at = given[last]  # (times, joints): the last sample up to there that gives the joint
    positions = np.where(at >= first[:, None], np.take_along_axis(chunk.positions, np.maximum(at, 0), axis=0), np.nan)
    frames = tuple(FrameTrack(f.parent, f.child, f.translation[last], f.quat_xyzw[last]) for f in chunk.frames)
    return SampleChunk(t[last], chunk.joints, positions, frames)


class ArraySource:
    """Samples already in memory (``times_ns (T,)``, ``positions (T, J)`` of ``joints``, full-length frame
    tracks) as a source, handed out in chunks."""

    def __init__(
        self,
        times_ns: I64,
        joints: Sequence[str],
        positions: F64,
        *,
        tracks: Sequence[FrameTrack] = (),
        clock: Clock = "duration",
    ) -> None:
        n = len(times_ns)
        if positions.shape != (n, len(joints)) or any(len(t.translation) != n or len(t.quat_xyzw) != n for t in tracks):
            raise ValueError(f"{n} times need positions of shape ({n}, {len(joints)}) and {n} poses per track")
        self.times_ns, self.joints, self.positions = times_ns, tuple(joints), positions
        self.tracks, self.clock = tuple(tracks), clock
        self.frames = tuple((t.parent, t.child) for t in self.tracks)

    def chunks(self, max_samples: int) -> Iterator[SampleChunk]:
        for start in range(0, len(self.times_ns), max_samples):
            part = slice(start, start + max_samples)
            tracks = tuple(FrameTrack(t.parent, t.child, t.translation[part], t.quat_xyzw[part]) for t in self.tracks)
            yield SampleChunk(self.times_ns[part], self.joints, self.positions[part], tracks)


@dataclass(frozen=True, eq=False)
class TfRecords:
    """Transforms as recorded (a bag's ``/tf`` or ``/tf_static``): one row per transform, each naming its frames."""

    times_ns: I64  # (n,) on the source's clock
    parents: tuple[str, ...]
    children: tuple[str, ...]
    translation: F64  # (n, 3) T_parent_child
    quat_xyzw: F64  # (n, 4)
    static: bool = False
    """From ``/tf_static``: each edge holds for the whole recording."""

    def __len__(self) -> int:
        return len(self.times_ns)

    def edges(self) -> set[tuple[str, str]]:
        return set(zip(self.parents, self.children, strict=True))

    def rows(self, keep: I64) -> TfRecords:
        """These records' rows at indices ``keep``."""
        return TfRecords(
            self.times_ns[keep],
            tuple(self.parents[i] for i in keep),
            tuple(self.children[i] for i in keep),
            self.translation[keep],
            self.quat_xyzw[keep],
            self.static,
        )


def tf_root(records: Sequence[TfRecords]) -> str | None:
    """The root of the recorded TF tree (a frame that is some edge's parent and no edge's child), as RViz users
    pick their fixed frame (``map``, ``odom``); with several roots, the one with the most frames below it."""
    children: dict[str, set[str]] = {}
    has_parent: set[str] = set()
    for r in records:
        for parent, child in r.edges():
            children.setdefault(parent, set()).add(child)
            has_parent.add(child)
    roots = [frame for frame in children if frame not in has_parent]
    if not roots:
        return None

    def below(frame: str) -> int:
        return len(reachable(children, frame))

    return max(sorted(roots), key=below)


def reachable(links: Mapping[str, Iterable[str]], start: str) -> set[str]:
    """The frames reached from ``start`` following ``links`` (frame → its neighbours), ``start`` included."""
    seen, stack = {start}, [start]
    while stack:
        for other in links.get(stack.pop(), ()):
            if other not in seen:
                seen.add(other)
                stack.append(other)
    return seen
