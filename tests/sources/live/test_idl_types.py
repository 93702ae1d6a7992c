"""Cyclone DDS types built from rosbags' definitions: the bytes cyclonedds-python writes for a message equal
rosbags' own ``serialize_cdr`` of it (an independent serializer), and a raw type keeps the bytes it is given."""

from __future__ import annotations

import numpy as np
import pytest

from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.sources.live.idl_types import IdlTypes, RawSample
from r2d2_viz.sources.live.names import LiveError

idl = pytest.importorskip("cyclonedds.idl")


def test_a_joint_state_serialises_as_rosbags_does() -> None:
    store = typestore("jazzy")
    types = IdlTypes(store, idl)
    JointState = types.struct("sensor_msgs/msg/JointState")
    Header, Time = types.struct("std_msgs/msg/Header"), types.struct("builtin_interfaces/msg/Time")
    assert JointState.__idl_typename__ == "sensor_msgs::msg::dds_::JointState_"
    ours = JointState(
        header=Header(stamp=Time(sec=12, nanosec=345), frame_id="base"),
        name=["tilt", "swivel"],
        position=[0.5, -1.25],
        velocity=[],
        effort=[],
    ).serialize()
    R = store.types
    theirs = store.serialize_cdr(
        R["sensor_msgs/msg/JointState"](
            R["std_msgs/msg/Header"](R["builtin_interfaces/msg/Time"](12, 345), "base"),
            ["tilt", "swivel"],
            np.array([0.5, -1.25]),
            np.zeros(0),
            np.zeros(0),
        ),
        "sensor_msgs/msg/JointState",
    )
    assert bytes(ours) == bytes(theirs)


def test_a_raw_type_keeps_the_bytes_and_names_the_same_dds_type() -> None:
    types = IdlTypes(typestore("jazzy"), idl)
    raw = types.raw_struct("std_msgs/msg/String")
    assert (
        raw.__idl_typename__ == types.struct("std_msgs/msg/String").__idl_typename__ == "std_msgs::msg::dds_::String_"
    )
    kept = raw.deserialize(b"\x00\x01\x00\x00\x03\x00\x00\x00hi\x00")
    assert isinstance(kept, RawSample) and kept.data == b"\x00\x01\x00\x00\x03\x00\x00\x00hi\x00"


def test_an_unknown_type_is_one_line() -> None:
    with pytest.raises(LiveError, match="message type control_msgs/msg/Nope is not known"):
        IdlTypes(typestore("jazzy"), idl).struct("control_msgs/msg/Nope")
