"""The page's joint sliders reach a real ROS 2 node: inside a loopback-only network namespace
(``tests/sources/live/sliders_scenario.py``), PyPI's rclpy node ``joint_states_listener.py`` listens to
``/joint_states`` while ``r2d2-viz --ros --urdf r2d2.urdf --motion sliders --serve --save`` runs, and the test POSTs
the page's move of ``tilt`` to −0.3. Expected values: the posted −0.3; the joints, their limits and where
joint_state_publisher starts them (0 when the range holds it, else its middle) from the URDF parsed by yourdfpy,
not r2d2-viz; joint_state_publisher's default rate (10 Hz), counted on the messages' own stamps (the publisher's
clock: no wall-clock of the test's)."""

from __future__ import annotations

import itertools
import json
import statistics
import sys
from pathlib import Path

import pytest
import yourdfpy
from rrd import read_recording
from sources.live import ros_node

from r2d2_viz.robot.model import default_urdf_path

pytestmark = pytest.mark.slow
TILT = -0.3
"""The move POSTed (sliders_scenario.MOVE)."""


def _starts(urdf: Path) -> dict[str, float]:
    """Every movable joint (not fixed, not a mimic: those follow their leader) → where joint_state_publisher starts
    it, from yourdfpy's parse of the URDF."""
    robot = yourdfpy.URDF.load(str(urdf), load_meshes=False, build_scene_graph=False).robot
    starts: dict[str, float] = {}
    for joint in robot.joints:
        if joint.type == "fixed" or joint.mimic is not None:
            continue
        limit = joint.limit
        lower, upper = (limit.lower, limit.upper) if limit is not None and joint.type != "continuous" else (None, None)
        if lower is None or upper is None or lower <= 0.0 <= upper:
            starts[joint.name] = 0.0
        else:
            starts[joint.name] = (lower + upper) / 2
    return starts


def test_a_slider_move_reaches_a_real_node(tmp_path: Path) -> None:
    python = ros_node.require_live("jazzy")
    urdf = default_urdf_path()
    starts = _starts(urdf)
    assert "tilt" in starts and len(starts) == 3, starts  # the R2D2: tilt, swivel, periscope
    script = Path(ros_node.__file__).with_name("sliders_scenario.py")
    exe = Path(sys.executable).parent / "r2d2-viz"
    command = [sys.executable, str(script), "--ros-python", str(python), "--cli", str(exe), "--urdf", str(urdf),
               "--out", str(tmp_path)]  # fmt: skip
    done = ros_node.in_netns(command, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["answer"] == [200, {"line": "tilt = -0.3"}], result["answer"]
    messages = result["messages"]
    assert messages, result["node_end"]
    for message in messages:  # every movable joint, each once, a position each
        assert sorted(message["name"]) == sorted(starts) and len(message["position"]) == len(starts), message
    poses = [dict(zip(m["name"], m["position"], strict=True)) for m in messages]
    # where the sliders start, until the move; then the posted tilt, the other joints where they were, to the end
    assert poses[0] == starts, poses[0]
    moved = next(i for i, pose in enumerate(poses) if pose["tilt"] != starts["tilt"])
    assert all(pose == starts for pose in poses[:moved])
    assert all(pose == {**starts, "tilt": TILT} for pose in poses[moved:]), poses[moved:]
    # about 10 Hz: at least 5 messages after the move, their stamps (the publisher's clock) spaced by about 0.1 s
    after = messages[moved:]
    assert len(after) >= 5, len(after)
    gaps = [b["stamp"] - a["stamp"] for a, b in itertools.pairwise(after)]
    assert 0.05 <= statistics.median(gaps) <= 0.2, gaps
    assert result["node_end"] == json.dumps({"received": len(messages)}), result["node_end"]
    assert result["app_rc"] == 0, result["stderr"][-5:]
    # and the same move in the recording, through the app's own subscription: it may match its own writer only
    # after the move (the node was up first), so the start value may or may not be there
    plot = read_recording(tmp_path / "app.rrd")["/joints/limited"]
    names = plot.static["SeriesLines:names"][-1]
    tilt = [row[names.index("tilt")] for row in plot.temporal["Scalars:scalars"]]
    assert tilt[-1] == TILT and set(tilt) <= {starts["tilt"], TILT}, tilt
