"""The cached Humble typestore and deserialisation that fails only with MsgError."""

from __future__ import annotations

import pytest
from msgs_build import T, cdr, header

from r2d2_viz.msgs.typestore import MsgError, deserialize, typestore


def test_cached_humble_store() -> None:
    assert typestore() is typestore()
    assert "visualization_msgs/msg/Marker" in typestore().types


def test_round_trip_and_failures() -> None:
    data = cdr(T("std_msgs/msg/Header")(**vars(header("/a", 1, 2))))
    msg = deserialize(memoryview(data), "std_msgs/msg/Header")
    assert (msg.frame_id, msg.stamp.sec, msg.stamp.nanosec) == ("/a", 1, 2)
    with pytest.raises(MsgError, match="too short"):
        deserialize(b"\x00", "std_msgs/msg/Header")
    with pytest.raises(MsgError, match="std_msgs/msg/Header: cannot deserialize"):
        deserialize(data[:-3], "std_msgs/msg/Header")
    with pytest.raises(MsgError):
        deserialize(data, "no_such/msg/Type")
    assert issubclass(MsgError, ValueError)
