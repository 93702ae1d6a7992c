"""Issue 19's transport against real Jazzy and Kilted rclpy nodes, joined late (and cyclonedds missing)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import pytest
from conftest import REPO

from r2d2_viz.sources.live import dds
from r2d2_viz.sources.live.names import LiveError

from . import ros_node

URDF = REPO / "assets" / "r2d2.urdf"


def test_missing_cyclonedds_names_the_pip_command(without_cyclonedds: None) -> None:
    with pytest.raises(LiveError, match="pip install 'cyclonedds"):
        dds.cyclonedds_modules()


def _scenario(distro: str, *extra: str) -> dict[str, Any]:
    python = ros_node.require_live(distro)
    script = Path(ros_node.__file__).with_name("scenario.py")
    command = [sys.executable, str(script), "--ros-python", str(python), "--urdf", str(URDF), *extra]
    done = ros_node.in_netns(command, timeout=90)
    assert done.returncode == 0, done.stderr[-3000:]
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


@pytest.mark.slow
def test_real_node_joined_late() -> None:
    """The node publishes first; we join late, get the latched description, every joint state, and /tf bytes.
    A Jazzy node: Kilted's (a second real node and scenario, 15 s of CPU) is joined late by the CLI in
    tests/test_live_run.py, which checks the description and every joint state arriving, through the same reader."""
    result = _scenario("jazzy", "--rate", "200", "--count", "400", "--tf-peer", "--deadline", "45")
    topics = {(t, ty): n for t, ty, n in result["topics"]}
    assert topics[("/joint_states", "sensor_msgs/msg/JointState")] == 1
    assert topics[("/robot_description", "std_msgs/msg/String")] == 1
    assert topics[("/tf", "tf2_msgs/msg/TFMessage")] == 1
    assert ["/robot_description", True, True] in result["qos"]  # latched: reliable + transient-local
    assert ["/joint_states", False, False] in result["qos"]  # best-effort matches any writer
    assert result["descriptions"] == [URDF.read_text()]
    assert result["node"]["matched"] and result["node"]["sent"] == 400
    assert result["names"] == ["tilt", "swivel", "periscope"]
    assert result["mismatches"] == 0
    assert result["joint_states"] >= 0.995 * 400, result
    assert result["tf"] > 0 and result["tf_equal"] == result["tf"], result  # == rosbags' serialize_cdr
    assert not any(result["dropped"].values())
