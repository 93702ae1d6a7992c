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


def test_list_names_real_nodes_and_their_topics() -> None:
    """``--ros --list`` names the nodes, as ``ros2 node list`` does, and per node its topics (``ros2 node info``):
    two real rclpy nodes (Jazzy, Fast DDS) in a loopback-only namespace. Expected from the nodes' own sources:
    publish_robot.py's node publishes /robot_description and /joint_states (and rclpy's /rosout and
    /parameter_events); tool_listener.py's subscribes to four tools' topics and publishes /map."""
    python = ros_node.require_live("jazzy")
    nodes = Path(ros_node.__file__).with_name("nodes")
    exe = str(Path(sys.executable).parent / "r2d2-viz")
    robot = f'"{python}" "{nodes / "publish_robot.py"}" --urdf "{URDF}" --subscribers 0 --count 150 --rate 10'
    listener = f'"{python}" "{nodes / "tool_listener.py"}" --seconds 20'
    listing = f'sleep 2; "{exe}" --ros --list; rc=$?; kill %1 %2; exit $rc'
    script = f"{robot} >/dev/null 2>&1 & {listener} >/dev/null 2>&1 & {listing}"
    done = ros_node.in_netns(["sh", "-c", script], timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert "node /r2d2_viz_test_robot" in lines, (done.stdout, done.stderr[-2000:])
    start = lines.index("node /r2d2_viz_test_robot")
    robot_lines = lines[
        start + 1 : next((i for i in range(start + 1, len(lines)) if not lines[i].startswith("  ")), len(lines))
    ]
    assert robot_lines == [
        "  publishes /joint_states [sensor_msgs/msg/JointState]",
        "  publishes /parameter_events [rcl_interfaces/msg/ParameterEvent]",
        "  publishes /robot_description [std_msgs/msg/String]",
        "  publishes /rosout [rcl_interfaces/msg/Log]",
    ], done.stdout
    start = lines.index("node /tool_listener")
    subscribed = [line for line in lines[start + 1 :] if line.startswith("  subscribes")]
    assert {line.split()[1] for line in subscribed} >= {"/clicked_point", "/goal_pose", "/initialpose", "/cmd_vel"}
    assert "  publishes /map [nav_msgs/msg/OccupancyGrid]" in lines[start + 1 :]


def test_list_names_kilted_nodes_and_keeps_a_lying_name_on_its_line() -> None:
    """``--ros --list`` beside a real Kilted node (rclpy 9.1, Fast DDS 3: Cyclone rejected the type information of
    its ros_discovery_info, so no node was named, and said so in its own lines on stderr) and a participant whose
    ros_discovery_info names a node with line breaks that print a node and a topic that do not exist
    (nodes/hostile_node_peer.py). Expected from the nodes' sources: tool_listener.py's node publishes /map; the
    peer's one node writes /chatter; its name prints on one line, each line break as ``\\x0a``."""
    python = ros_node.require_live("kilted")
    nodes = Path(ros_node.__file__).with_name("nodes")
    exe = str(Path(sys.executable).parent / "r2d2-viz")
    listener = f'"{python}" "{nodes / "tool_listener.py"}" --seconds 25'
    peer = f'"{sys.executable}" "{nodes / "hostile_node_peer.py"}" 25'
    listing = f'sleep 2; "{exe}" --ros --list; rc=$?; kill $a $b 2>/dev/null; exit $rc'
    script = f"{listener} >/dev/null 2>&1 & a=$!; {peer} >/dev/null 2>&1 & b=$!; {listing}"
    done = ros_node.in_netns(["sh", "-c", script], timeout=120, env={"R2D2_VIZ_DEBUG": ""})
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    lie = "node /evil\\x0anode /fake\\x0a  publishes /fake_topic [std_msgs/msg/String]"
    assert {line for line in lines if line.startswith("node ")} == {"node /tool_listener", lie}, done.stdout
    assert lines[lines.index(lie) + 1] == "  publishes /chatter [std_msgs/msg/String]"
    assert "  publishes /map [nav_msgs/msg/OccupancyGrid]" in lines[lines.index("node /tool_listener") + 1 :]
    assert done.stderr == "", done.stderr  # nothing of Cyclone's own ("dq.builtin: … invalid type object")


def test_cyclones_own_lines_are_off_unless_debugging() -> None:
    """Cyclone prints its warnings to the process's stderr itself; a deprecated element in ``CYCLONEDDS_URI`` makes
    it say one when the domain is joined: heard with ``R2D2_VIZ_DEBUG=1`` only."""
    if (missing := ros_node.netns_missing()) is not None:
        ros_node.unavailable(missing)
    deprecated = "<General><NetworkInterfaceAddress>lo</NetworkInterfaceAddress></General>"
    uri = f"<CycloneDDS><Domain>{deprecated}</Domain></CycloneDDS>"
    join = "from r2d2_viz.sources.live.dds import LiveGraph\nwith LiveGraph():\n    pass"
    runs = {
        debug: ros_node.in_netns([sys.executable, "-c", join], 60, env={"CYCLONEDDS_URI": uri, "R2D2_VIZ_DEBUG": debug})
        for debug in ("", "1")
    }
    assert runs[""].returncode == 0 and runs[""].stderr == "", runs[""].stderr
    assert runs["1"].returncode == 0 and "deprecated element" in runs["1"].stderr, runs["1"].stderr


@pytest.mark.parametrize("peer", ["nonexistent.invalid", "::1"])
def test_a_static_peer_cyclone_cannot_resolve_is_one_line(peer: str) -> None:
    """Cyclone aborts the process (SIGABRT, exit 134) on a static peer it cannot resolve — a name that does not
    resolve (``.invalid`` never does, RFC 2606), or an IPv6 address while it runs on IPv4 — so it is refused first."""
    if (missing := ros_node.netns_missing()) is not None:
        ros_node.unavailable(missing)
    exe = str(Path(sys.executable).parent / "r2d2-viz")
    done = ros_node.in_netns([exe, "--ros", "--list"], 60, env={"ROS_STATIC_PEERS": f"127.0.0.1;{peer}"})
    assert done.returncode == 2 and done.stderr.count("\n") == 1, (done.returncode, done.stderr)
    assert f"ROS_STATIC_PEERS: cannot resolve '{peer}'" in done.stderr and not done.stdout
