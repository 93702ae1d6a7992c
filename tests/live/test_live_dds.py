"""Issue 19's transport: ROS 2 names and environment (unit), then real Jazzy and Kilted nodes, joined late."""

from __future__ import annotations

import builtins
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

from r2d2_viz.errors import R2d2VizError
from r2d2_viz.sources.live import dds
from r2d2_viz.sources.live.names import (
    DiscoveryRange,
    LiveError,
    RosDiscovery,
    dds_topic,
    dds_type,
    ros_topic,
    ros_type,
)

from . import ros_node

URDF = Path(__file__).resolve().parents[2] / "assets" / "r2d2.urdf"


def test_names_round_trip() -> None:
    assert dds_topic("/joint_states") == "rt/joint_states"
    assert ros_topic("rt/robot/joint_states") == "/robot/joint_states"
    assert ros_topic("DCPSPublication") is None
    assert dds_type("sensor_msgs/msg/JointState") == "sensor_msgs::msg::dds_::JointState_"
    assert ros_type("tf2_msgs::msg::dds_::TFMessage_") == "tf2_msgs/msg/TFMessage"
    assert ros_type("HelloWorld") is None
    for bad in ("joint_states", "/", "/a b"):
        with pytest.raises(LiveError, match="not a ROS 2 topic"):
            dds_topic(bad)
    with pytest.raises(LiveError, match="not a ROS 2 type"):
        dds_type("JointState")
    assert issubclass(LiveError, R2d2VizError)


@pytest.mark.parametrize(
    ("env", "domain", "expected_range", "peers"),
    [
        ({}, 0, DiscoveryRange.SUBNET, ()),
        ({"ROS_DOMAIN_ID": "42", "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}, 42, DiscoveryRange.LOCALHOST, ()),
        ({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET", "ROS_STATIC_PEERS": "10.0.0.2; robot"}, 0,
         DiscoveryRange.SUBNET, ("10.0.0.2", "robot")),
        ({"ROS_AUTOMATIC_DISCOVERY_RANGE": "OFF", "ROS_STATIC_PEERS": "x"}, 0, DiscoveryRange.OFF, ()),
        ({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SYSTEM_DEFAULT"}, 0, DiscoveryRange.SYSTEM_DEFAULT, ()),
        ({"ROS_LOCALHOST_ONLY": "1", "ROS_STATIC_PEERS": "x", "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}, 0,
         DiscoveryRange.LOCALHOST, ()),
        ({"ROS_AUTOMATIC_DISCOVERY_RANGE": "nonsense"}, 0, DiscoveryRange.LOCALHOST, ()),
    ],
)  # fmt: skip
def test_environment_mapping(env: dict[str, str], domain: int, expected_range: DiscoveryRange, peers: Any) -> None:
    found = RosDiscovery.from_env(env)
    assert (found.domain_id, found.range, found.static_peers) == (domain, expected_range, peers)
    root = ET.fromstring(found.cyclone_xml(pid=7))
    assert root.findtext("Domain/Compatibility/IgnoreTypeInformation") == "1.15"  # eProsima's vendor id
    multicast = root.findtext("Domain/General/AllowMulticast")
    addresses = [p.get("address") for p in root.iter("Peer")]
    if expected_range is DiscoveryRange.LOCALHOST:
        assert multicast == "false" and addresses == ["localhost"]
    elif expected_range is DiscoveryRange.OFF:
        assert multicast == "false" and root.findtext("Domain/Discovery/Tag") == "ros_discovery_off_7"
    else:
        assert multicast is None and addresses == list(peers)


def test_bad_domain_and_warnings() -> None:
    for bad in ("x", "300", "-1"):
        with pytest.raises(LiveError, match="ROS_DOMAIN_ID"):
            RosDiscovery.from_env({"ROS_DOMAIN_ID": bad})
    assert RosDiscovery.from_env({"ROS_AUTOMATIC_DISCOVERY_RANGE": "nonsense"}).warnings


def test_missing_cyclonedds_names_the_pip_command(monkeypatch: pytest.MonkeyPatch) -> None:
    real_import = builtins.__import__

    def no_cyclone(name: str, *args: Any, **kwargs: Any) -> Any:
        if name.startswith("cyclonedds"):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    for name in [m for m in sys.modules if m.startswith("cyclonedds")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setattr(builtins, "__import__", no_cyclone)
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
@pytest.mark.parametrize("distro", ["jazzy", "kilted"])
def test_real_node_joined_late(distro: str) -> None:
    """The node publishes first; we join late, get the latched description, every joint state, and /tf bytes."""
    result = _scenario(distro, "--rate", "200", "--count", "400", "--tf-peer", "--deadline", "45")
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
