"""A block of one topic's messages cut at a time (what a feed logs of it by then): receive times inclusive, the
rows with them, the bytes shared out."""

from __future__ import annotations

import numpy as np
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.msgs.blocks.telemetry_blocks import ImuBlock, decode_imu_block
from r2d2_viz.msgs.shapes import DecodeOptions
from r2d2_viz.sources.topic_blocks import TopicBlock

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types


def _block() -> TopicBlock:
    v3 = T["geometry_msgs/msg/Vector3"]
    messages = []
    for k in range(5):
        header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](k, 0), "imu")
        quat = T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0)
        imu = T["sensor_msgs/msg/Imu"](header, quat, np.zeros(9), v3(k, 0, 0), np.zeros(9), v3(0, k, 0), np.zeros(9))
        messages.append(bytes(STORE.serialize_cdr(imu, "sensor_msgs/msg/Imu")))
    block = decode_imu_block(messages, DecodeOptions())
    assert block is not None
    times = np.array([10, 20, 20, 30, 40], dtype=np.int64)
    return TopicBlock(times, "/imu", "sensor_msgs/msg/Imu", block, 1000)


def test_split_takes_what_was_received_by_then() -> None:
    block = _block()
    head, tail = block.split(20)  # both messages received at 20
    assert head is not None and tail is not None
    assert head.times_ns.tolist() == [10, 20, 20] and tail.times_ns.tolist() == [30, 40]
    assert isinstance(head.block, ImuBlock) and isinstance(tail.block, ImuBlock)
    assert head.block.angular_velocity[:, 0].tolist() == [0, 1, 2]  # the rows go with their times
    assert tail.block.linear_acceleration[:, 1].tolist() == [3, 4]
    assert head.nbytes + tail.nbytes == 1000 and head.nbytes == 600


def test_split_before_or_after_everything() -> None:
    block = _block()
    assert block.split(9) == (None, block)
    assert block.split(40) == (block, None)
    assert len(block) == 5
