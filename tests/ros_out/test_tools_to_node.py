"""RViz's tools reach a real ROS 2 node: inside a loopback-only network namespace
(``tests/sources/live/tools_scenario.py``), PyPI's rclpy node ``tool_listener.py`` listens while ``r2d2-viz --ros
--serve`` runs on a graph with ``/tf`` (root ``map``) and a map, and the test POSTs to the page's event endpoint
what the page's JavaScript sends for each tool (``r2d2_viz/viewer/web/page.js``). Expected values: the positions
posted, worked by hand (a 45° heading is the quaternion (0, 0, sin 22.5°, cos 22.5°)), RViz's constants
(rviz_default_plugins' initial_pose_tool.cpp covariance) and the TF root as the fixed frame — not r2d2-viz's code.
The same chain with headless Chromium clicking the page: tests/e2e/test_web_tools.py (opt-in, minutes)."""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import pytest
from sources.live import ros_node

pytestmark = pytest.mark.slow
RVIZ_COVARIANCE = {0: 0.25, 7: 0.25, 35: 0.06853891945200942}
"""rviz_default_plugins/src/rviz_default_plugins/tools/pose_estimate/initial_pose_tool.cpp: x, y and yaw."""
S = math.sqrt(0.5)
GOAL = {"frame": "map", "position": [1.0, 2.0, 0.0], "xyzw": [0.0, 0.0, math.sin(math.pi / 8), math.cos(math.pi / 8)]}
"""From (1, 2) towards (2, 3): 45°, on the ground (RViz's goal has z = 0)."""
ESTIMATE = {"frame": "map", "position": [-1.5, 0.5, 0.0], "xyzw": [0.0, 0.0, -S, S]}
"""From (-1.5, 0.5) towards (-1.5, -2.5): -90°."""


def test_each_tool_reaches_a_real_node(tmp_path: Path) -> None:
    python = ros_node.require_live("jazzy")
    script = Path(ros_node.__file__).with_name("tools_scenario.py")
    exe = Path(sys.executable).parent / "r2d2-viz"
    command = [sys.executable, str(script), "--ros-python", str(python), "--cli", str(exe), "--out", str(tmp_path)]
    done = ros_node.in_netns(command, timeout=240)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    received = result["received"]
    assert set(received) == {"/clicked_point", "/goal_pose", "/initialpose", "/cmd_vel"}, received
    # nothing from the two requests without the token (they asked for (9, 9, 0)): 404, and no point
    assert result["no_token"] == [404, 404]
    assert received["/clicked_point"] == [{"frame": "map", "point": [2.5, -1.25, 0.3]}]
    [goal] = received["/goal_pose"]
    [estimate] = received["/initialpose"]
    for got, expected in ((goal, GOAL), (estimate, ESTIMATE)):
        assert got["frame"] == expected["frame"] and got["position"] == expected["position"]
        assert got["xyzw"] == pytest.approx(expected["xyzw"], abs=1e-12)
    assert estimate["covariance"] == [RVIZ_COVARIANCE.get(i, 0.0) for i in range(36)]
    # forward while held, stopped on release; how many forward twists the node gets is DDS's business (a reliable
    # writer of depth 1, as RViz's: a newer one may replace one not yet acknowledged), and the app's 0.5 s guard may
    # stop a teleop in between on a starved machine
    twists = [(t["linear"], t["angular"]) for t in received["/cmd_vel"]]
    assert (0.5, 0.0) in twists and set(twists) <= {(0.5, 0.0), (0.0, 0.0)} and twists[-1] == (0.0, 0.0), twists
    # each event answered with its line, which the app also printed; the run ended cleanly
    lines = result["stdout"].splitlines()
    said = {
        "clicked": "clicked: map (2.50, -1.25, 0.30) → /clicked_point",
        "goal": "goal: map (1.00, 2.00) yaw 45.0° → /goal_pose",
        "estimate": "initial pose: map (-1.50, 0.50) yaw -90.0° → /initialpose",
        "forward": "teleop: 0.50 m/s, 0.00 rad/s → /cmd_vel",
        "stop": "teleop: stopped → /cmd_vel",
    }
    statuses, answers = zip(*result["answers"], strict=True)
    assert set(statuses) == {200}
    forward = len(answers) - 4  # held until the node had a forward twist: at least one
    assert forward >= 1 and list(answers) == [{"line": said[k]} for k in ("clicked", "goal", "estimate")] + [
        {"line": said["forward"]}
    ] * forward + [{"line": said["stop"]}]
    assert lines[:4] == [said[k] for k in ("clicked", "goal", "estimate", "forward")], lines
    assert lines[-1] == said["stop"] and set(lines[3:]) <= {said["forward"], said["stop"]}, lines
    assert result["app_rc"] == 0, result["stderr"][-5:]
    # the app heard the node (its map) and the TF root became the fixed frame the messages are in
    [heard] = [line for line in result["stderr"] if line.startswith("r2d2-viz: received ")]
    assert re.search(r"/map [1-9]", heard) and re.search(r"/tf [1-9]", heard), heard
