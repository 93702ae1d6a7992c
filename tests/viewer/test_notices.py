"""Warnings: once each, on stderr and /warnings, static or at a time on either clock."""

from __future__ import annotations

from pathlib import Path

import rerun as rr
from rrd import read_recording

from r2d2_viz.viewer.notices import Notices


def test_once_per_key_static_or_timed(tmp_path: Path) -> None:
    out = tmp_path / "n.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    said: list[str] = []
    notices = Notices(rec, warn=said.append)
    notices.report("model note")
    notices.report("model note")
    notices.report("joint a left its limits", key="limits:a", at_ns=2_500_000_000)
    notices.report("joint a left its limits again", key="limits:a", at_ns=3_000_000_000)
    rec.flush()
    rec.disconnect()
    assert said == ["model note", "joint a left its limits"] and notices.said("limits:a")
    rows = read_recording(out)["/warnings"]
    assert rows.static["TextLog:text"] == [["model note"]]
    assert rows.times == [2_500_000_000] and rows.temporal["TextLog:level"][0] == ["WARN"]


def test_a_timestamp_clock(tmp_path: Path) -> None:
    out = tmp_path / "t.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    Notices(rec, warn=lambda _: None).report("bag note", at_ns=1_700_000_000_000_000_000, clock="timestamp")
    rec.flush()
    rec.disconnect()
    assert read_recording(out)["/warnings"].times == [1_700_000_000_000_000_000]


def test_a_frame_name_with_terminal_escapes_is_shown_not_sent(tmp_path: Path) -> None:
    """A warning naming a bag's frame ``base\\x1b]0;owned\\x07`` (an escape that sets a terminal's title) lands in
    /warnings with the escape shown as text, no ESC or BEL byte (issue 36); what the terminal gets is warn's."""
    out = tmp_path / "e.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    said: list[str] = []
    Notices(rec, warn=said.append).report("frame base\x1b]0;owned\x07: \x1b[31mnot in the tree\x1b[0m")
    rec.flush()
    rec.disconnect()
    texts = read_recording(out)["/warnings"].static["TextLog:text"]
    assert texts == [["frame base\\x1b]0;owned\\x07: not in the tree"]]  # by hand
