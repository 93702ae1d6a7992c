"""Several robots on a live graph: which robots the settle saw (the end-to-end run with real ROS 2 nodes is
tests/sources/test_robots.py::test_two_live_robots_of_both_conventions)."""

from __future__ import annotations

from r2d2_viz.sources.live.source import LiveBatch
from r2d2_viz.viewer.live_robots import robot_namespaces


def test_several_robots_are_named_and_one_keeps_the_single_robot_names() -> None:
    two = [LiveBatch(robot_descriptions=[("/robot2", "<robot/>")]), LiveBatch(robot_descriptions=[("/robot1", "x")])]
    assert robot_namespaces(two) == ("/robot1", "/robot2")
    assert robot_namespaces([LiveBatch(descriptions=["<robot/>"]), *two[:1]]) == ("", "/robot2")
    assert robot_namespaces(two[:1]) == () and robot_namespaces([LiveBatch(descriptions=["x"])]) == ()
