"""Where display rows go: the recording itself, or a stand-in that gathers them as columns (issue 46, item 3:
:class:`r2d2_viz.viewer.blocks.row_columns.RowColumns`), which :mod:`r2d2_viz.viewer.displays` logs to alike."""

from __future__ import annotations

from typing import Protocol

import rerun as rr

from r2d2_viz.msgs import shapes

NUMBERS = (shapes.Arrows, shapes.Boxes, shapes.Ellipsoids, shapes.Cylinders, shapes.LineStrips, shapes.Text)
"""What gathered rows take as plain numbers (:mod:`r2d2_viz.viewer.blocks.row_items`), never as archetypes: a
decoded message of these alone is not prepared ahead."""


class Rows(Protocol):
    """Display rows gathered as columns (:class:`r2d2_viz.viewer.blocks.row_columns.RowColumns`)."""

    def log(self, entity: str, first: rr.AsComponents, *extra: rr.AsComponents, static: bool = False) -> None:
        """As ``rec.log``: a row of archetypes at the time given last."""

    def at(self, time_ns: int) -> None:
        """The time of the rows logged next."""

    def take(self, entity: str, item: shapes.Shape, frame: str) -> bool:
        """Whether ``item`` (in ``frame``; "" for none) was taken as a row of numbers, not archetypes."""


Recorder = rr.RecordingStream | Rows
"""The recording, or rows gathered for it."""
