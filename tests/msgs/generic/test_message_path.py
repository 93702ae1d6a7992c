"""Foxglove's message paths (the common cases), checked against a definition: the answers worked out by hand from
Humble's .msg files (nav_msgs/Odometry, sensor_msgs/JointState, sensor_msgs/NavSatFix)."""

from __future__ import annotations

import re

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


@pytest.mark.parametrize("text", ["odom.x", "/odom", "/odom.", "/odom.a[", "/odom.a[:].b", "/odom.a{b==1}", "/od-om.x"])
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


@pytest.mark.parametrize(
    ("text", "field", "filters"),
    [
        ("/scan.ranges[-1]", "ranges[-1]", ()),
        ("/scan.ranges[:]", "ranges[:]", ()),
        ('/cmd{header.frame_id=="left"}.twist.linear.x', "twist.linear.x", (("header.frame_id", "==", "left"),)),
        ("/cmd{x>=3}{y!=-1.5}.a[0].b", "a[0].b", (("x", ">=", 3.0), ("y", "!=", -1.5))),
        ("/cmd{ok==true}.v", "v", (("ok", "==", True),)),
    ],
)
def test_foxglove_forms_negative_indices_and_filters_on_the_topic(text: str, field: str, filters: tuple) -> None:
    path = parse_path(text, {"/scan", "/cmd"})
    assert path.field == field and path.topic == text.split(".")[0].split("{")[0]
    assert [(f.field, f.op, f.value) for f in path.filters] == list(filters)


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("/js.position[01]", "leading zero"),
        ("/js.points[:].x", "end of a path only"),
        ("/js.position[1:3]", "slice with bounds"),
        ("/js.a{b==1}.c", "filter inside the path"),
        ("/js.position[$i]", "variables"),
        ("/js{b~1}.c", "a filter is {FIELD OP VALUE}"),
    ],
)
def test_a_refused_form_is_named(text: str, named: str) -> None:
    with pytest.raises(MsgError, match=re.escape(named)):
        parse_path(text)


def test_a_filter_passes_what_compares_so_and_text_never_equals_a_number() -> None:
    import numpy as np

    from r2d2_viz.msgs.generic.message_path import Filter

    assert Filter("x", ">=", 2.0).mask(np.array([1.0, 2.0, 3.0])).tolist() == [False, True, True]
    assert Filter("f", "==", "a").mask(np.array(["a", "b"], dtype=object)).tolist() == [True, False]
    assert Filter("f", "==", 1.0).mask(np.array(["1"], dtype=object)).tolist() == [False]


@pytest.mark.parametrize(
    ("msgtype", "field", "why"),
    [
        (FIX, "position_covariance[-9]", None),
        (FIX, "position_covariance[-10]", "position_covariance has 9 items"),
        (JOINTS, "effort[-1]", None),
        (JOINTS, "header.frame_id", None),  # text: a filter may compare it
        (JOINTS, "position[:]", None),
        (JOINTS, "name[:]", "name is not an array of numbers (a slice is read of those only)"),
    ],
)
def test_negative_indices_and_text_for_filters_are_checked(msgtype: str, field: str, why: str | None) -> None:
    assert check_field(typestore(), msgtype, field, text=True) == why
