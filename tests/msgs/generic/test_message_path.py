"""Foxglove's message paths (the common cases), checked against a definition: the answers worked out by hand from
Humble's .msg files (nav_msgs/Odometry, sensor_msgs/JointState, sensor_msgs/NavSatFix)."""

from __future__ import annotations

import pytest

from r2d2_viz.msgs.generic.message_path import check_field, field_names, parse_path
from r2d2_viz.msgs.typestore import MsgError, typestore

ODOM, JOINTS, FIX = "nav_msgs/msg/Odometry", "sensor_msgs/msg/JointState", "sensor_msgs/msg/NavSatFix"


@pytest.mark.parametrize(
    ("text", "topic", "field"),
    [
        ("/odom.twist.twist.linear.x", "/odom", "twist.twist.linear.x"),
        ("/joint_states.effort[2]", "/joint_states", "effort[2]"),
        ("/panda_arm_controller/state.error.positions[0]", "/panda_arm_controller/state", "error.positions[0]"),
    ],
)
def test_a_path_is_a_topic_and_a_field(text: str, topic: str, field: str) -> None:
    path = parse_path(text)
    assert (path.topic, path.field, path.text) == (topic, field, text)


def test_the_longest_known_topic_wins() -> None:
    assert parse_path("/a/b.c", {"/a", "/a/b"}).topic == "/a/b"


@pytest.mark.parametrize("text", ["odom.x", "/odom", "/odom.", "/odom.a[", "/odom.a[:]", "/odom.a{b==1}", "/od-om.x"])
def test_what_is_not_a_path_is_a_msg_error(text: str) -> None:
    with pytest.raises(MsgError):
        parse_path(text)


@pytest.mark.parametrize(
    ("msgtype", "field", "why"),
    [
        (ODOM, "twist.twist.linear.x", None),
        (JOINTS, "effort[2]", None),  # a sequence: any index may be there
        (FIX, "position_covariance[8]", None),
        (FIX, "position_covariance[9]", "position_covariance has 9 items"),  # float64[9]
        (ODOM, "twist.twist.linear.q", "nav_msgs/msg/Odometry has no field q there"),
        (ODOM, "twist.twist.linear", "twist.twist.linear is a message, not a number"),
        (ODOM, "child_frame_id", "child_frame_id is text, not a number"),
        (JOINTS, "effort", "effort is an array: give an index (effort[0])"),
        (ODOM, "pose[0]", "pose is not an array"),
    ],
)
def test_a_field_is_checked_against_the_definition(msgtype: str, field: str, why: str | None) -> None:
    assert check_field(typestore(), msgtype, field) == why


def test_field_names_as_paths_name_them() -> None:
    assert field_names(typestore(), JOINTS) == [
        "header.stamp.sec",
        "header.stamp.nanosec",
        "header.frame_id",
        "name[i]",
        "position[i]",
        "velocity[i]",
        "effort[i]",
    ]
