"""A ``--compare`` recording's own entities: each run's fixed frame under the view's frame, and the summary."""

from __future__ import annotations

from pathlib import Path

import rerun as rr
from rrd import read_recording

from r2d2_viz.viewer.compare.merge import RunStyle
from r2d2_viz.viewer.compare.scene import COMPARE_FRAME, SUMMARY, anchor, log_summary, tint


def test_the_first_run_is_drawn_as_it_is_the_others_tinted_and_translucent() -> None:
    assert tint(0) is None
    assert tint(1) == (255, 140, 0, 100) and tint(2) == (30, 144, 255, 100)
    assert tint(7) == tint(1)  # six tints, then again


def test_each_runs_fixed_frame_hangs_from_the_views_frame_and_the_summary_is_a_document(tmp_path: Path) -> None:
    out = tmp_path / "scene.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    anchor(rec, RunStyle("b", 0), "odom", (0.0, 2.0, 0.0))
    log_summary(rec, ["runs: a, b", "duration: a 1 s · b 2 s"])
    rec.flush()
    rec.disconnect()
    recording = read_recording(out)
    edge = recording["/runs/b/anchor"].static
    assert edge["Transform3D:parent_frame"][-1] == [COMPARE_FRAME] and edge["Transform3D:child_frame"][-1] == ["b/odom"]
    assert edge["Transform3D:translation"][-1] == [[0.0, 2.0, 0.0]]
    assert recording[SUMMARY].static["TextDocument:text"][-1] == ["runs: a, b\nduration: a 1 s · b 2 s"]
