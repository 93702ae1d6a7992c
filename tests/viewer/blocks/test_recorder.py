"""Where display rows go: the recording, or rows gathered as columns; both take the display logging alike."""

from __future__ import annotations

import numpy as np
import rerun as rr

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.shapes import Decoded
from r2d2_viz.viewer.blocks.recorder import NUMBERS, Rows
from r2d2_viz.viewer.blocks.row_columns import RowColumns
from r2d2_viz.viewer.displays import log_decoded, prepare


def test_gathered_rows_are_rows_and_numbers_are_not_prepared_ahead() -> None:
    rec = rr.RecordingStream("test_recorder")
    rows: Rows = RowColumns(rec, "time", "timestamp")  # (mypy: a RowColumns is Rows)
    arrows = shapes.Arrows(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32), np.zeros((0, 4), np.uint8), 0.1)
    assert isinstance(arrows, NUMBERS)
    decoded = Decoded("base_link", 0, (arrows,))
    assert prepare(decoded) is None  # taken as numbers when logged: no archetypes built ahead for nothing
    log_decoded(rows, "/pose", decoded, timeline="time", time_ns=5)
    assert isinstance(rows, RowColumns)
    assert [g.times_ns for g in rows.runs["/pose"]] == [[5]] and rows.runs["/pose"][0].builders is not None
    points = shapes.Points(np.zeros((1, 3), np.float32), np.zeros((0, 4), np.uint8), 0.1)
    assert prepare(Decoded("base_link", 0, (points,))) is not None  # not a kind taken as numbers: built ahead
