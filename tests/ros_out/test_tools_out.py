"""What the tools send, as RViz sends it: each message read back with rosbags' own deserializer and compared with
values worked out by hand (a 45° heading is the quaternion (0, 0, sin 22.5°, cos 22.5°)); RViz's initial pose
covariance as rviz_default_plugins' initial_pose_tool.cpp sets it (0.25, 0.25, 0.06853891945200942)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.ros_out.tools_out import PICK_CALLBACKS, TELEOP_TIMEOUT_S, ToolOutput

STORE = get_typestore(Stores.ROS2_JAZZY)
STAMP = 1_700_000_000_123_456_789


class Graph:
    def __init__(self) -> None:
        self.sent: list[tuple[str, str, Any]] = []

    def publish(self, topic: str, ros_type: str, data: bytes) -> None:
        self.sent.append((topic, ros_type, STORE.deserialize_cdr(data, ros_type)))


def _output(graph: Graph | None, lines: list[str], now: list[float] | None = None, **kw: Any) -> ToolOutput:
    clock = (lambda: now[0]) if now is not None else (lambda: 0.0)
    return ToolOutput("map", publisher=graph, say=lines.append, clock=clock, stamp=lambda: STAMP, **kw)


def test_each_tool_sends_what_rviz_sends() -> None:
    graph, lines = Graph(), []
    out = _output(graph, lines)
    out.handle({"tool": "Publish Point", "points": [[1.234, -4.561, 0.012]], "entity": "/tools/ground"})
    out.handle({"tool": "2D Goal Pose", "points": [[1, 1, 0.01], [2, 2, 0.4]]})
    out.handle({"tool": "2D Pose Estimate", "points": [[0, 0, 0], [0, -3, 0]]})
    out.handle({"tool": "Measure", "points": [[0, 0, 0], [3, 4, 0]]})
    assert [(t, m) for t, m, _ in graph.sent] == [
        ("/clicked_point", "geometry_msgs/msg/PointStamped"),
        ("/goal_pose", "geometry_msgs/msg/PoseStamped"),
        ("/initialpose", "geometry_msgs/msg/PoseWithCovarianceStamped"),
    ]  # Measure publishes nothing
    point, goal, estimate = (msg for _, _, msg in graph.sent)
    for msg in (point, goal, estimate):
        assert msg.header.frame_id == "map"
        assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (1_700_000_000, 123_456_789)
    assert (point.point.x, point.point.y, point.point.z) == (1.234, -4.561, 0.012)
    p, q = goal.pose.position, goal.pose.orientation
    assert (p.x, p.y, p.z) == (1.0, 1.0, 0.0)  # z = 0, whatever the click's height
    assert np.allclose([q.x, q.y, q.z, q.w], [0, 0, math.sin(math.pi / 8), math.cos(math.pi / 8)])
    q = estimate.pose.pose.orientation  # from (0, 0) towards (0, -3): -90°
    assert np.allclose([q.x, q.y, q.z, q.w], [0, 0, -math.sqrt(0.5), math.sqrt(0.5)])
    expected = np.zeros(36)
    expected[0], expected[7], expected[35] = 0.25, 0.25, 0.06853891945200942
    assert np.array_equal(estimate.pose.covariance, expected)
    assert lines == [
        "clicked: map (1.23, -4.56, 0.01) → /clicked_point",
        "goal: map (1.00, 1.00) yaw 45.0° → /goal_pose",
        "initial pose: map (0.00, 0.00) yaw -90.0° → /initialpose",
        "measured: 5.000 m in map from (0.00, 0.00, 0.00) to (3.00, 4.00, 0.00)",
    ]


def test_without_a_graph_the_tools_print_and_call_back() -> None:
    lines: list[str] = []
    picks: list[Any] = []
    PICK_CALLBACKS.append(picks.append)
    try:
        out = _output(None, lines, topics={"Publish Point": "/p"})
        assert out.handle({"tool": "Publish Point", "points": [[1.23, -4.56, 0]]}) == "clicked: map (1.23, -4.56, 0.00)"
    finally:
        PICK_CALLBACKS.remove(picks.append)
    assert lines == ["clicked: map (1.23, -4.56, 0.00)"] and picks[0].points == ((1.23, -4.56, 0.0),)
    assert out.topics["Publish Point"] == "/p" and out.topics["2D Goal Pose"] == "/goal_pose"


def test_teleop_stops_on_release_on_silence_and_on_close() -> None:
    graph, lines, now = Graph(), [], [0.0]
    out = _output(graph, lines, now)
    for k in range(3):  # held: 10 Hz
        now[0] = k * 0.1
        out.handle({"tool": "Teleop", "linear": 0.5, "angular": -1.0})
    out.handle({"tool": "Teleop", "linear": 0, "angular": 0})  # released
    twists = [(m.linear.x, m.angular.z) for t, _, m in graph.sent]
    assert twists == [(0.5, -1.0)] * 3 + [(0.0, 0.0)] and {t for t, _, _ in graph.sent} == {"/cmd_vel"}
    assert lines == ["teleop: 0.50 m/s, -1.00 rad/s → /cmd_vel", "teleop: stopped → /cmd_vel"]  # said on change
    graph.sent.clear()
    now[0] = 1.0
    out.handle({"tool": "Teleop", "linear": 0.2, "angular": 0})
    now[0] = 1.0 + TELEOP_TIMEOUT_S / 2
    assert not out.check_teleop()
    now[0] = 1.0 + TELEOP_TIMEOUT_S * 1.5  # the page went quiet while moving: the zero is sent for it
    assert out.check_teleop() and not out.check_teleop()
    out.handle({"tool": "Teleop", "linear": 0.2, "angular": 0})
    out.close()  # the app stops: so does the robot
    assert [(m.linear.x, m.angular.z) for _, _, m in graph.sent] == [(0.2, 0.0), (0.0, 0.0), (0.2, 0.0), (0.0, 0.0)]


def test_a_goal_clicked_on_a_drawn_sphere_lands_on_the_ground_under_the_pointer() -> None:
    """As found: after a Publish Point at (2, 1, 0), the app draws a 0.08 m sphere there; a goal clicked on it
    took the sphere's surface. RViz's pose tools take the click's ray on z = 0, whatever is drawn. By hand: the eye
    at (-3, 1, 5) looks along (5, 0, -5) at (2, 1, 0); the ray meets the sphere where (5 - 5s)^2 * 2 = 0.08^2, so
    s = 1 - 0.08 / (5 sqrt 2), at (-3 + 5s, 1, 5 - 5s) = (1.94343, 1, 0.05657): the point the viewer reports. The
    ground point of that ray is (2, 1, 0); the heading click is on the ground at (3, 2, 0): 45°."""
    graph, lines = Graph(), []
    out = _output(graph, lines)
    s = 1 - 0.08 / (5 * math.sqrt(2))
    on_sphere = [-3 + 5 * s, 1.0, 5 - 5 * s]
    event = {"tool": "2D Goal Pose", "points": [on_sphere, [3.0, 2.0, 0.0]], "entity": "/tools/ground"}
    out.handle({**event, "eye": [-3.0, 1.0, 5.0]})
    ((_, _, goal),) = graph.sent
    p, q = goal.pose.position, goal.pose.orientation
    assert np.allclose([p.x, p.y, p.z], [2.0, 1.0, 0.0], atol=1e-12)
    assert np.allclose([q.x, q.y, q.z, q.w], [0, 0, math.sin(math.pi / 8), math.cos(math.pi / 8)])
    assert lines == ["goal: map (2.00, 1.00) yaw 45.0° → /goal_pose"]
    # Publish Point keeps the surface it was clicked on, as RViz's does
    out.handle({"tool": "Publish Point", "points": [on_sphere], "eye": [-3.0, 1.0, 5.0]})
    assert np.allclose([graph.sent[-1][2].point.x, graph.sent[-1][2].point.z], [on_sphere[0], on_sphere[2]])
