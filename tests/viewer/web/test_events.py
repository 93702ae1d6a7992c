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
        ({"tool": "Publish Point", "points": [[0, 0, 0]], "topic": "/cmd_vel"}, "expected only points, entity and eye"),
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


def test_pose_tools_take_the_ray_on_the_ground() -> None:
    """By hand: from the eye (0, 0, 10) through (1, 2, 5), half-way down, the ray meets z = 0 at (2, 4, 0); through
    (1, 1, 0) (the ground itself) at (1, 1, 0). A ray going up, or an eye under the ground, meets no ground."""
    pick = parse_event({"tool": "2D Goal Pose", "points": [[1, 2, 5], [1, 1, 0]], "eye": [0, 0, 10]})
    assert isinstance(pick, Pick) and pick.eye == (0.0, 0.0, 10.0)
    assert pick.on_ground().points == ((2.0, 4.0, 0.0), (1.0, 1.0, 0.0))
    no_eye = parse_event({"tool": "2D Goal Pose", "points": [[1, 2, 5], [1, 1, 0]]})
    assert isinstance(no_eye, Pick) and no_eye.on_ground().points == ((1.0, 2.0, 0.0), (1.0, 1.0, 0.0))
    for eye in ([0, 0, 4], [0, 0, -1]):
        up = parse_event({"tool": "2D Goal Pose", "points": [[1, 2, 5], [1, 1, 0]], "eye": eye})
        with pytest.raises(ToolEventError, match="does not meet the ground"):
            assert isinstance(up, Pick)
            up.on_ground()
    with pytest.raises(ToolEventError, match=r"the eye is \[x, y, z\]"):
        parse_event({"tool": "2D Goal Pose", "points": [[0, 0, 0], [1, 1, 0]], "eye": [0, 0]})
