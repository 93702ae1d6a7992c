"""RViz's tools in r2d2-viz's page, end to end: a real ROS 2 node (PyPI's rclpy) receives what headless Chromium
clicked in the page of ``r2d2-viz --ros --serve``, all inside a loopback-only network namespace
(``tests/sources/live/tools_scenario.py --browser``, the browser's part: ``web_tools_browser.py``), on a graph with
``/tf`` and a map (the node's, transient local as map_server's). The expected values come from the positions the
viewer itself reported for each click (``selection_change`` events), RViz's own constants and the map the node sent
(its origin, resolution and size), not from r2d2-viz's code. Opt-in (minutes); the same chain without the browser
(the page's events POSTed as its JavaScript sends them) runs by default: tests/ros_out/test_tools_to_node.py."""

from __future__ import annotations

import json
import math
import os
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from rrd import read_recording
from sources.live import ros_node
from sources.live.nodes.tool_listener import MAP_ORIGIN, MAP_RESOLUTION, MAP_SIZE

from . import viewers

pytestmark = [pytest.mark.e2e, pytest.mark.slow]
RVIZ_COVARIANCE = {0: 0.25, 7: 0.25, 35: 0.06853891945200942}
"""rviz_default_plugins/src/rviz_default_plugins/tools/pose_estimate/initial_pose_tool.cpp: x, y and yaw."""


def _yaw(xyzw: list[float]) -> float:
    x, y, z, w = xyzw
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


@pytest.mark.skipif(
    not os.environ.get("R2D2_VIZ_TOOLS_E2E"),
    reason="the browser clicking each tool for a real ROS 2 node takes 1.6-4 minutes on 2 cores (SwiftShader draws "
    "each frame): run it with R2D2_VIZ_TOOLS_E2E=1 (a real node receiving the page's events without a browser: "
    "tests/ros_out/test_tools_to_node.py)",
)
def test_each_tool_reaches_a_real_node(artifacts_dir: Path) -> None:
    missing = viewers.missing_web_prerequisites()
    if missing:
        ros_node.unavailable("; ".join(missing))
    python = ros_node.require_live("jazzy")
    script = Path(ros_node.__file__).with_name("tools_scenario.py")
    exe = Path(sys.executable).parent / "r2d2-viz"
    command = [sys.executable, str(script), "--ros-python", str(python), "--cli", str(exe), "--out", str(artifacts_dir),
               "--browser"]  # fmt: skip
    done = ros_node.in_netns(command, timeout=400)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    picks, received = result["picks"], result["received"]
    assert [p["tool"] for p in picks] == ["Publish Point", "2D Goal Pose", "2D Goal Pose", "2D Pose Estimate",
                                          "2D Pose Estimate"]  # fmt: skip
    # Publish Point: the point the viewer reported, in the fixed frame — and nothing from the requests without
    # the token (they asked for (9, 9, 0))
    assert received["/clicked_point"] == [{"frame": "map", "point": picks[0]["position"]}]
    assert result["no_token"] == [404, 404]
    for topic, (first, second) in (("/goal_pose", picks[1:3]), ("/initialpose", picks[3:5])):
        [pose] = received[topic]
        x0, y0, _ = first["position"]
        x1, y1, _ = second["position"]
        assert pose["frame"] == "map" and pose["position"] == [x0, y0, 0.0]
        assert math.isclose(_yaw(pose["xyzw"]), math.atan2(y1 - y0, x1 - x0), abs_tol=1e-9), topic
    covariance = received["/initialpose"][0]["covariance"]
    assert covariance == [RVIZ_COVARIANCE.get(i, 0.0) for i in range(36)]
    twists = [(t["linear"], t["angular"]) for t in received["/cmd_vel"]]
    # forward while held, stopped on release: how many forward commands the hold sends is the browser's timers'
    # business (a starved page sends fewer, and the app's 0.5 s guard may stop it in between), so not counted
    assert (0.5, 0.0) in twists and set(twists) <= {(0.5, 0.0), (0.0, 0.0)} and twists[-1] == (0.0, 0.0), twists
    lines = result["stdout"].splitlines()
    x, y, z = picks[0]["position"]
    assert f"clicked: map ({x:.2f}, {y:.2f}, {z:.2f}) → /clicked_point" in lines
    assert any(line.startswith("goal: map (") and line.endswith("→ /goal_pose") for line in lines)
    assert lines[-1] == "teleop: stopped → /cmd_vel" and result["app_rc"] == 0
    # the node's map arrived (its frame, map, the TF root, is the fixed frame) and the pickable ground covers it
    # (a 600 x 400 map of 0.1 m cells from (-30, -20): to (30, 20)), not the 50 m default
    [received] = [line for line in result["stderr"] if line.startswith("r2d2-viz: received ")]
    assert re.search(r"/map [1-9]", received), received
    rows = read_recording(artifacts_dir / "app.rrd")
    assert "/map" in rows
    ground = next(v for k, v in rows["/tools/ground"].static.items() if "vertex_positions" in k)[-1]
    (x0, y0), (width, height) = MAP_ORIGIN, MAP_SIZE
    x1, y1 = x0 + width * MAP_RESOLUTION, y0 + height * MAP_RESOLUTION
    assert np.allclose(ground, [[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0]])
