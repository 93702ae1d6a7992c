"""Warnings: once each, on stderr and /warnings, every one a row of the time line (issue 44, item 17): one said
without a time at the run's first time, none static (a static row hides every timed one from the Warnings view, and
the view shows no static row: see r2d2_viz/viewer/notices.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
from rrd import read_recording

from r2d2_viz.viewer.notices import Notices


def _saved(tmp_path: Path) -> tuple[rr.RecordingStream, Path]:
    out = tmp_path / "n.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    return rec, out


def _closed(rec: rr.RecordingStream, out: Path) -> dict:  # type: ignore[type-arg]
    rec.flush()
    rec.disconnect()
    return read_recording(out)


def test_once_per_key_at_the_start_or_at_its_time(tmp_path: Path) -> None:
    rec, out = _saved(tmp_path)
    said: list[str] = []
    notices = Notices(rec, warn=said.append)  # a generated motion's: the duration since the start, from 0
    notices.report("model note")
    notices.report("model note")
    notices.report("joint a left its limits", key="limits:a", at_ns=2_500_000_000)
    notices.report("joint a left its limits again", key="limits:a", at_ns=3_000_000_000)
    rows = _closed(rec, out)["/warnings"]
    assert said == ["model note", "joint a left its limits"] and notices.said("limits:a")
    assert not rows.static  # nothing static: it would hide the timed rows
    assert rows.times == [0, 2_500_000_000]
    assert rows.temporal["TextLog:text"] == [["model note"], ["joint a left its limits"]]
    assert rows.temporal["TextLog:level"] == [["WARN"], ["WARN"]]


def test_a_timestamp_clock_and_the_runs_first_time(tmp_path: Path) -> None:
    rec, out = _saved(tmp_path)
    start = 1_700_000_000_000_000_000
    notices = Notices(rec, warn=lambda _: None, at_ns=start, clock="timestamp")
    notices.report("no robot")
    notices.report("bag note", at_ns=start + 7)
    rows = _closed(rec, out)["/warnings"]
    assert rows.times == [start, start + 7] and not rows.static


def test_a_report_leaves_the_callers_time_alone(tmp_path: Path) -> None:
    """A warning said between a caller's ``set_time`` and its ``log`` (a mesh missing while a message is drawn)
    does not move where the caller's row goes."""
    rec, out = _saved(tmp_path)
    rec.set_time("time", duration=np.timedelta64(5, "s"))
    Notices(rec, warn=lambda _: None).report("said in between")
    rec.log("/thing", rr.Points3D([[0.0, 0.0, 0.0]]))
    recording = _closed(rec, out)
    assert recording["/thing"].times == [5_000_000_000] and recording["/warnings"].times == [0]


def test_a_frame_name_with_terminal_escapes_is_shown_not_sent(tmp_path: Path) -> None:
    """A warning naming a bag's frame ``base\\x1b]0;owned\\x07`` (an escape that sets a terminal's title) lands in
    /warnings with the escape shown as text, no ESC or BEL byte (issue 36); what the terminal gets is warn's."""
    rec, out = _saved(tmp_path)
    said: list[str] = []
    Notices(rec, warn=said.append).report("frame base\x1b]0;owned\x07: \x1b[31mnot in the tree\x1b[0m")
    texts = _closed(rec, out)["/warnings"].temporal["TextLog:text"]
    assert texts == [["frame base\\x1b]0;owned\\x07: not in the tree"]]  # by hand
