"""ROS 2 names on DDS and the discovery environment, as rcl and rmw_cyclonedds read them (by hand)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import pytest

from r2d2_viz.errors import R2d2VizError
from r2d2_viz.sources.live.names import (
    DiscoveryRange,
    LiveError,
    RosDiscovery,
    dds_topic,
    dds_type,
    ros_topic,
    ros_type,
)


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
    # asked, never demanded (no min): a 1.2 MB cloud's fragments fit; a kernel that gives less is no error
    assert root.find("Domain/Internal/SocketReceiveBufferSize").attrib == {"max": "8MB"}
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


def test_where_discovery_looked_is_said_as_the_environment_set_it() -> None:
    env = {"ROS_DOMAIN_ID": "7", "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET", "ROS_STATIC_PEERS": "10.0.0.2;robot.lan"}
    assert RosDiscovery.from_env(env).searched() == (
        "ROS_DOMAIN_ID 7, discovery range SUBNET (this machine's networks, by multicast, and the static peers "
        "10.0.0.2, robot.lan)"
    )
    assert RosDiscovery.from_env({"ROS_LOCALHOST_ONLY": "1"}).searched() == (
        "ROS_DOMAIN_ID 0, discovery range LOCALHOST (this machine only)"
    )
