"""Warnings for the user: one line on stderr (or wherever ``warn`` sends it) and a ``TextLog`` row on
``/warnings`` on the run's time line; each reported once.

Every row has a time: one said with its own (a joint leaving its limits) at that time, the others (a missing mesh,
an impossible inertia, an ``--rviz`` note, "no robot": what a run says as it loads) at :attr:`Notices.at_ns`, the
run's first time (:mod:`r2d2_viz.sources.start`). Nothing on ``/warnings`` is static: Rerun keeps one static row
per entity and component (each replaces the last), a static component hides every timed row of it from queries,
and the Warnings view (a ``TextLogView``: a range query on the selected timeline) shows no static row at all — a
robot missing a mesh had nothing there to say why. The rows go out as columns (``rr.send_columns``), so a report
never moves the time a caller set for its own ``rec.log`` calls.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np
import rerun as rr

from r2d2_viz.errors import warn
from r2d2_viz.msgs.telemetry import shown
from r2d2_viz.sources.base import Clock
from r2d2_viz.sources.start import plan_start_ns
from r2d2_viz.viewer.columns import encoded, send, time_array
from r2d2_viz.viewer.entities import TIMELINE, WARNINGS

if TYPE_CHECKING:
    from r2d2_viz.sources.plan import RunPlan

Warn = Callable[[str], None]
to_stderr: Warn = warn
"""The default: a whole ``warning:`` line on stderr."""


class Notices:
    """Reports each message (or each ``key``) once. ``at_ns`` (on ``clock``): where a warning said without its own
    time goes — the run's first time (``--watch`` moves it to each reload's)."""

    def __init__(
        self,
        rec: rr.RecordingStream,
        *,
        warn: Warn = to_stderr,
        timeline: str = TIMELINE,
        at_ns: int = 0,
        clock: Clock = "duration",
    ) -> None:
        self.rec, self.warn, self.timeline = rec, warn, timeline
        self.at_ns, self.clock = at_ns, clock
        self._said: set[str] = set()

    def said(self, key: str) -> bool:
        return key in self._said

    def report(
        self, message: str, *, key: str | None = None, at_ns: int | None = None, clock: Clock | None = None
    ) -> None:
        """Warn once per ``key`` (the message by default), at ``at_ns`` on ``clock`` (default: :attr:`at_ns`)."""
        key = message if key is None else key
        if key in self._said:
            return
        self._said.add(key)
        self.warn(message)
        when = np.array([self.at_ns if at_ns is None else at_ns], dtype=np.int64)
        row = rr.TextLog.columns(text=[shown(message)], level=[rr.TextLogLevel.WARN])  # a frame name may hold escapes
        send(self.rec, WARNINGS, self.timeline, time_array(when, clock or self.clock), encoded(row))


class _Said(Protocol):
    notices: Notices


def run_notices(rec: rr.RecordingStream, plan: RunPlan, clock: Clock, streams: Sequence[_Said] = ()) -> Notices:
    """The notices of a planned run (its untimed warnings at the run's first time), shared by its robots' streams."""
    notices = Notices(rec, at_ns=plan_start_ns(plan), clock=clock)
    for stream in streams:
        stream.notices = notices
    return notices
