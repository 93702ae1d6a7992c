"""Each item taken as a row of numbers makes the very components Rerun's own archetypes make of it (the reference:
Rerun's converters, through :func:`r2d2_viz.viewer.displays.archetypes` / ``rr.TextLog`` … as logged before issue
46): same descriptors, same Arrow values, row for row, two rows a column."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr

from r2d2_viz.msgs import shapes
from r2d2_viz.viewer.blocks.recorder import NUMBERS
from r2d2_viz.viewer.blocks.row_items import row_of
from r2d2_viz.viewer.displays import archetypes

POSE = shapes.Pose((1.0, 2.0, 3.0), (0.0, 0.0, 0.6, 0.8))
RED, BLUE = np.array([[255, 0, 0, 255]], np.uint8), np.array([[0, 0, 255, 128], [9, 8, 7, 6]], np.uint8)
TWO = np.array([[0.5, 0.25, 0.125], [1, 2, 3]], np.float32)
QUATS = np.array([[0, 0, 0, 1], [0.6, 0, 0, 0.8]], np.float32)
ITEMS: dict[str, list[shapes.Shape]] = {  # two of each kind: a column of two rows
    "arrows": [
        shapes.Arrows(np.zeros((2, 3), np.float32), TWO, BLUE, 0.01, POSE),
        shapes.Arrows(np.zeros((1, 3), np.float32), TWO[:1], np.zeros((0, 4), np.uint8), 0.0),
    ],
    "boxes": [shapes.Boxes(TWO, TWO, QUATS, BLUE, POSE), shapes.Boxes(TWO[:1], TWO[1:], QUATS[1:], RED)],
    "ellipsoids": [shapes.Ellipsoids(TWO, TWO, QUATS, BLUE), shapes.Ellipsoids(TWO[:1], TWO[1:], QUATS[:1], RED, POSE)],
    "cylinders": [
        shapes.Cylinders(TWO, np.array([1, 2], np.float32), np.array([0.1, 0.2], np.float32), QUATS, BLUE, POSE),
        shapes.Cylinders(TWO[:1], np.ones(1, np.float32), np.ones(1, np.float32), QUATS[:1], RED),
    ],
    "strips": [shapes.LineStrips((TWO, TWO[:1] * 2), BLUE, 0.05, POSE), shapes.LineStrips((TWO,), RED, 0.02)],
    "thin strips": [shapes.LineStrips((TWO,), RED, 0.0)],  # no radius: RViz's thin line
    "text": [
        shapes.Text("hello", (1.0, 2.0, 3.0), 0.2, (1, 2, 3, 4), POSE),
        shapes.Text("", (0, 0, 0), 1, (0, 0, 0, 0)),
    ],
}


def _theirs(item: shapes.Shape, frame: str) -> dict[str, list[object]]:
    """What ``rec.log`` of the item sent: its frame, then its archetypes' batches (the first of a descriptor)."""
    out: dict[str, list[object]] = {}
    for archetype in [rr.CoordinateFrame(frame), *archetypes(item)] if frame else archetypes(item):
        for batch in archetype.as_component_batches():
            array = batch.as_arrow_array()
            if array is not None:
                out.setdefault(str(batch.component_descriptor()), array.to_pylist())
    return out


def _ours(items: list[shapes.Shape], frame: str) -> list[dict[str, list[object]]]:
    """The rows of ``items`` as columns, read back row by row."""
    rows = [row_of(item, frame) for item in items]
    assert all(row is not None for row in rows)
    out: list[dict[str, list[object]]] = [{} for _ in items]
    for j, (descriptor, build, _) in enumerate(rows[0]):  # type: ignore[index]
        values, lengths = build([row[j][2] for row in rows])  # type: ignore[index]
        assert isinstance(values, pa.Array)
        start = 0
        for i, n in enumerate(lengths):
            out[i][str(descriptor)] = values.slice(start, int(n)).to_pylist()
            start += int(n)
    return out


@pytest.mark.parametrize("kind", list(ITEMS))
def test_a_shape_is_the_row_its_archetypes_make(kind: str) -> None:
    items = ITEMS[kind]
    assert _ours(items, "base_link") == [_theirs(item, "base_link") for item in items]


def test_plain_items_are_the_rows_log_plain_made() -> None:
    cases = [
        ([shapes.Series("", ("a", "b"), np.array([1.5, np.nan]))], [rr.Scalars(np.array([1.5, np.nan]))]),
        ([shapes.LogLine("WARN", "hot")], [rr.TextLog("hot", level="WARN")]),
        ([shapes.LogLine("", "plain")], [rr.TextLog("plain", level=None)]),
        ([shapes.GeoPoint(48.5, 2.25)], [rr.GeoPoints(lat_lon=[[48.5, 2.25]], radii=rr.Radius.ui_points(6.0))]),
    ]
    for items, logged in cases:
        want = {str(b.component_descriptor()): b.as_arrow_array().to_pylist() for b in logged[0].as_component_batches()}
        got = _ours(items, "")[0]
        np.testing.assert_equal(got, want)


def test_every_kind_gathered_rows_take_as_numbers_has_a_row() -> None:
    """What :data:`NUMBERS` names is not prepared ahead as archetypes: each must have its row of numbers."""
    taken = {type(item) for items in ITEMS.values() for item in items}
    assert set(NUMBERS) == taken
    assert row_of(ITEMS["boxes"][0], "") is None  # a shape in no frame: as archetypes (the feed names one first)
    assert row_of(shapes.GridMap(np.zeros((1, 1, 4), np.uint8), 1.0), "map") is None
