"""The page's tool events: what the tools send is accepted and typed; anything else is refused, in one line."""

from __future__ import annotations

import math

import pytest

from r2d2_viz.errors import ToolEventError
from r2d2_viz.viewer.web.events import Drive, Pick, parse_event


def test_picks_and_drives_are_typed() -> None:
    pick = parse_event({"tool": "2D Goal Pose", "points": [[1, 1, 0.01], [2, 2, 0.3]], "entity": "/tools/ground"})
    assert pick == Pick("2D Goal Pose", ((1.0, 1.0, 0.01), (2.0, 2.0, 0.3)), "/tools/ground")
    assert isinstance(pick, Pick) and math.isclose(pick.yaw, math.pi / 4)  # by hand: 45° from (1, 1) to (2, 2)
    measure = parse_event({"tool": "Measure", "points": [[0, 0, 0], [3, 4, 0]]})
    assert isinstance(measure, Pick) and measure.distance == 5.0  # a 3-4-5 triangle
    point = parse_event({"tool": "Publish Point", "points": [[1.23, -4.56, 0]], "entity": None})
    assert isinstance(point, Pick) and point.points == ((1.23, -4.56, 0.0),)
    assert parse_event({"tool": "Teleop", "linear": 0.5, "angular": -1}) == Drive(0.5, -1.0)
    assert not Drive(0.0, 0.0).moving and Drive(0.0, 0.1).moving


@pytest.mark.parametrize(
    ("event", "said"),
    [
        ({"tool": "Select", "points": [[0, 0, 0]]}, "unknown tool 'Select'"),
        ({"points": [[0, 0, 0]]}, "unknown tool 'None'"),
        ({"tool": "Publish Point", "points": [[0, 0, 0], [1, 1, 1]]}, "expected 1 clicked point"),
        ({"tool": "2D Goal Pose", "points": [[0, 0, 0]]}, "expected 2 clicked points"),
        ({"tool": "Publish Point", "points": [[0, 0]]}, "a point is [x, y, z]"),
        ({"tool": "Publish Point", "points": [[0, "1", 0]]}, "expected a finite number"),
        ({"tool": "Publish Point", "points": [[0, float("nan"), 0]]}, "expected a finite number"),
        ({"tool": "Publish Point", "points": [[0, 1e9, 0]]}, "out of range"),
        ({"tool": "Publish Point", "points": [[0, True, 0]]}, "expected a finite number"),
        ({"tool": "Publish Point", "points": [[0, 0, 0]], "topic": "/cmd_vel"}, "expected only points and entity"),
        ({"tool": "Publish Point", "points": [[0, 0, 0]], "entity": 3}, "entity is an entity path"),
        ({"tool": "Teleop", "linear": 100, "angular": 0}, "out of range"),
        ({"tool": "Teleop", "linear": 1}, "expected a finite number"),
        ({"tool": "Teleop", "linear": 1, "angular": 0, "topic": "/x"}, "expected only linear and angular"),
    ],
)
def test_anything_else_is_refused(event: dict[str, object], said: str) -> None:
    with pytest.raises(ToolEventError, match=None) as info:
        parse_event(event)
    assert said in str(info.value) and "\n" not in str(info.value)
