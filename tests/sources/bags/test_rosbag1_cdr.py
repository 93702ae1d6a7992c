"""ROS 1 → CDR many messages at a time: every row must be, byte for byte, what rosbags' own ROS 1 → CDR conversion
(with the store ``rosbags-convert`` builds: Noetic's types, ROS 2's Header) makes of that message; a batch whose
messages differ in shape is refused (converted one by one by the caller)."""

from __future__ import annotations

from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.msgs.definitions import from_ros1, own_store
from r2d2_viz.sources.bags.rosbag1_cdr import byte_map, convert_batch

NOETIC = get_typestore(Stores.ROS1_NOETIC)
T = NOETIC.types
REFERENCE = get_typestore(Stores.EMPTY)
REFERENCE.register(
    {**NOETIC.fielddefs, "std_msgs/msg/Header": get_typestore(Stores.ROS2_HUMBLE).fielddefs["std_msgs/msg/Header"]}
)


def _header(k: int, frame: str = "base") -> Any:
    return T["std_msgs/msg/Header"](seq=k, stamp=T["builtin_interfaces/msg/Time"](sec=k, nanosec=7), frame_id=frame)


def _vec(x: float) -> Any:
    return T["geometry_msgs/msg/Vector3"](x=x, y=-x, z=0.5)


def _joint_state(k: int, names: tuple[str, ...] = ("a", "bb", "c")) -> Any:
    n = len(names)
    return T["sensor_msgs/msg/JointState"](
        header=_header(k), name=list(names), position=np.arange(n) + 0.25 * k, velocity=np.zeros(0), effort=np.ones(n)
    )


def _imu(k: int) -> Any:
    q = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=np.sin(k), w=np.cos(k))
    cov = np.arange(9.0) * k
    return T["sensor_msgs/msg/Imu"](
        header=_header(k, "imu"),
        orientation=q,
        orientation_covariance=cov,
        angular_velocity=_vec(k),
        angular_velocity_covariance=cov,
        linear_acceleration=_vec(2 * k),
        linear_acceleration_covariance=cov,
    )


def _batch(typename: str, msgs: list[Any]) -> tuple[np.ndarray | None, list[bytes]]:
    definition, _ = NOETIC.generate_msgdef(typename, ros_version=1)
    raws = [bytes(NOETIC.serialize_ros1(m, typename)) for m in msgs]
    expected = [bytes(REFERENCE.ros1_to_cdr(r, typename)) for r in raws]
    rows = np.frombuffer(b"".join(raws), np.uint8).reshape(len(raws), -1)
    store = own_store(typename, definition, "ros1msg")
    return convert_batch(store, typename, from_ros1(typename, definition), rows), expected


def test_batches_match_rosbags_byte_for_byte() -> None:
    cases = {
        "sensor_msgs/msg/JointState": [_joint_state(k) for k in range(50)],
        "sensor_msgs/msg/Imu": [_imu(k) for k in range(50)],
        "geometry_msgs/msg/Vector3": [_vec(k) for k in range(20)],
    }
    for typename, msgs in cases.items():
        got, expected = _batch(typename, msgs)
        assert got is not None, typename
        assert [bytes(row) for row in got] == expected, typename


def test_strings_of_other_contents_but_one_length_batch_and_other_shapes_do_not() -> None:
    msgs = [_joint_state(k, ("j1", f"x{k % 10}")) for k in range(30)]
    got, expected = _batch("sensor_msgs/msg/JointState", msgs)
    assert got is not None and [bytes(row) for row in got] == expected
    # one total length, another shape: names 'ab' + 'c' against 'a' + 'bc'
    mixed = [_joint_state(k, ("ab", "c") if k % 2 else ("a", "bc")) for k in range(10)]
    got, _ = _batch("sensor_msgs/msg/JointState", mixed)
    assert got is None


def test_the_byte_map_is_checked_on_a_probe() -> None:
    definition, _ = NOETIC.generate_msgdef("sensor_msgs/msg/JointState", ros_version=1)
    store = own_store("sensor_msgs/msg/JointState", definition, "ros1msg")
    raw = bytes(NOETIC.serialize_ros1(_joint_state(3), "sensor_msgs/msg/JointState"))
    convert = from_ros1("sensor_msgs/msg/JointState", definition)
    cdr, src, dst, lengths = byte_map(store, "sensor_msgs/msg/JointState", raw, convert)
    assert cdr == bytes(REFERENCE.ros1_to_cdr(raw, "sensor_msgs/msg/JointState"))
    # by hand: the lengths of frame_id, name, 'a', 'bb', 'c', position, velocity, effort
    assert len(src) == len(dst) and len(lengths) == 4 * 8
    assert int(src.min()) == 4  # the header's seq (bytes 0-3) is not copied

    def lying(data: bytes | memoryview) -> memoryview:  # a converter that moves one byte: the probe sees it
        out = bytearray(convert(data))
        out[-1], out[-2] = out[-2], out[-1]
        return memoryview(bytes(out))

    try:
        byte_map(store, "sensor_msgs/msg/JointState", raw, lying)
    except ValueError:
        pass
    else:
        raise AssertionError("a wrong conversion passed the probe")
