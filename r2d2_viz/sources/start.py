"""Where a run starts on its time line: the time of the warnings it says as it loads (a missing mesh, an impossible
inertia, an ``--rviz`` note, "no robot"), so the viewer's Warnings view, which shows the rows of a timeline, shows
them from the start (:mod:`r2d2_viz.viewer.notices`).

* a generated motion: 0 (its clock is the duration since the start; its first sample is at 0);
* a bag: the first receive time of the replayed stretch (the bag's first message; a seek's pre-roll included) — with
  ``--time header``, the earliest stamp of the joint states and transforms the plan read ahead, when there are any;
* a live graph: the earliest time of what the settle received (joint states, transforms, display and other topics'
  messages; else the source timestamps of what came: joint states are held until there is a robot), else the wall
  clock as the run starts (what the source timestamp of the next message will be near).
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from typing import TYPE_CHECKING

from r2d2_viz.sources.base import SampleChunk, TfRecords

if TYPE_CHECKING:
    from r2d2_viz.sources.live.source import LiveBatch
    from r2d2_viz.sources.plan import RunPlan


def plan_start_ns(plan: RunPlan) -> int:
    """The first time of a planned run on its timeline (see the module docstring)."""
    replay = plan.replay
    if replay is None:
        return 0
    first = replay.segments[0].start_ns if replay.segments else None  # a seek's pre-roll comes first
    received = replay.span[0] if first is None else first
    if replay.time != "header":
        return received
    stamps = _earliest([plan.preview_joints], [plan.moving_tf])
    return received if stamps is None else stamps


def live_start_ns(batches: Iterable[LiveBatch], now_ns: int | None = None) -> int:
    """The first time of a live run: the earliest of what the settle's ``batches`` hold, else ``now_ns`` (default:
    the wall clock)."""
    batches = list(batches)
    chunks = [c for b in batches for c in (b.joints, *b.robot_joints.values())]
    messages = [m.time_ns for b in batches for m in (*b.displays, *b.fields)]
    earliest = _earliest(chunks, [r for b in batches for r in b.tf], messages)
    if earliest is not None:
        return earliest
    received = [s.source_timestamp_ns for b in batches for s in b.samples]  # joint states held until a robot comes
    if received:
        return min(received)
    return time.time_ns() if now_ns is None else now_ns


def _earliest(
    chunks: Iterable[SampleChunk | None], records: Iterable[TfRecords | None], times: Iterable[int] = ()
) -> int | None:
    """The earliest time of the samples ``chunks`` hold, of the moving transforms in ``records`` and of ``times``."""
    found = [int(c.times_ns.min()) for c in chunks if c is not None and len(c)]
    found += [int(r.times_ns.min()) for r in records if r is not None and not r.static and len(r)]
    found += [int(t) for t in times]
    return min(found) if found else None
