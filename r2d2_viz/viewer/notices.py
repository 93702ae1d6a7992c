"""Warnings for the user: one line on stderr (or wherever ``warn`` sends it) and a ``TextLog`` row on
``/warnings``, static or at a time; each reported once."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import rerun as rr

from r2d2_viz.errors import warn
from r2d2_viz.msgs.telemetry import shown
from r2d2_viz.sources.base import Clock
from r2d2_viz.viewer.entities import TIMELINE, WARNINGS

Warn = Callable[[str], None]
to_stderr: Warn = warn
"""The default: a whole ``warning:`` line on stderr."""


class Notices:
    """Reports each message (or each ``key``) once."""

    def __init__(self, rec: rr.RecordingStream, *, warn: Warn = to_stderr, timeline: str = TIMELINE) -> None:
        self.rec, self.warn, self.timeline = rec, warn, timeline
        self._said: set[str] = set()

    def said(self, key: str) -> bool:
        return key in self._said

    def report(
        self, message: str, *, key: str | None = None, at_ns: int | None = None, clock: Clock = "duration"
    ) -> None:
        """Warn once per ``key`` (the message by default); static unless ``at_ns`` (on ``clock``) is given."""
        key = message if key is None else key
        if key in self._said:
            return
        self._said.add(key)
        self.warn(message)
        row = rr.TextLog(shown(message), level=rr.TextLogLevel.WARN)  # a bag's frame name may hold escapes
        if at_ns is None:
            self.rec.log(WARNINGS, row, static=True)
            return
        if clock == "duration":
            self.rec.set_time(self.timeline, duration=np.timedelta64(at_ns, "ns"))
        else:
            self.rec.set_time(self.timeline, timestamp=np.datetime64(at_ns, "ns"))
        self.rec.log(WARNINGS, row)
