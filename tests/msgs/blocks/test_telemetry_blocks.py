"""The Imu block decoder against rosbags: messages written by rosbags' own serializer (random values, frame ids of
every length 0-12 and a leading '/', little- and big-endian CDR), read back by rosbags' ``deserialize_cdr`` — the
golden values; and the orientation axes against the per-message decoder, message by message."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.msgs.blocks.telemetry_blocks import ImuBlock, decode_imu_block
from r2d2_viz.msgs.registry import BLOCK_DECODERS, decode
from r2d2_viz.msgs.shapes import Arrows, Decoded, DecodeOptions, Series

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types
IMU = "sensor_msgs/msg/Imu"


def _imu(rng: np.random.Generator, frame: str, q: tuple[float, ...] | None = None, cov0: float | None = None) -> object:
    v3, quat = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    stamp = T["builtin_interfaces/msg/Time"](int(rng.integers(-(2**31), 2**31)), int(rng.integers(0, 10**9)))
    covs = [rng.normal(size=9) for _ in range(3)]
    if cov0 is not None:
        covs[0][0] = cov0
    return T[IMU](
        T["std_msgs/msg/Header"](stamp, frame),
        quat(*(q if q is not None else rng.normal(size=4))),
        covs[0],
        v3(*rng.normal(size=3) * 10),
        covs[1],
        v3(*rng.normal(size=3) * 10),
        covs[2],
    )


FRAMES = ["", "a", "ab", "abc", "imu", "imu_", "/imu_link", "imu_link", "imu_link_1", "imu_link_12", "電池", "x" * 12]
ODD_Q = [
    (0.0, 0.0, 0.0, 0.0),
    (math.nan, 0.0, 0.0, 1.0),
    (math.inf, 0.0, 0.0, 1.0),
    (1e-10, 0.0, 0.0, 0.0),
    (1e300,) * 4,
]


@pytest.fixture(scope="module")
def messages() -> tuple[list[object], list[bytes]]:
    """200 Imu messages in both byte orders: random values, frame ids of varied lengths, odd orientations."""
    rng = np.random.default_rng(46)
    msgs = [_imu(rng, FRAMES[k % len(FRAMES)]) for k in range(150)]
    msgs += [_imu(rng, "imu_link", q) for q in ODD_Q] + [_imu(rng, "imu_link", cov0=-1.0) for _ in range(5)]
    msgs += [_imu(rng, FRAMES[k % len(FRAMES)]) for k in range(40)]
    data = [bytes(STORE.serialize_cdr(m, IMU, little_endian=k % 3 != 0)) for k, m in enumerate(msgs)]
    assert {d[:2] for d in data} == {b"\x00\x00", b"\x00\x01"}  # rosbags wrote big- and little-endian CDR
    return msgs, data


def test_the_registry_names_the_imu_block_decoder() -> None:
    assert BLOCK_DECODERS[IMU] is decode_imu_block


def test_every_field_is_what_rosbags_reads(messages: tuple[list[object], list[bytes]]) -> None:
    _, data = messages
    block = decode_imu_block(data, DecodeOptions())
    assert isinstance(block, ImuBlock) and len(block) == len(data)
    for k, raw in enumerate(data):
        msg = STORE.deserialize_cdr(raw, IMU)  # the golden values: rosbags' deserializer
        stamp = msg.header.stamp
        assert block.stamps_ns[k] == stamp.sec * 1_000_000_000 + stamp.nanosec
        frame = msg.header.frame_id
        assert block.frames[block.frame_index[k]] == (frame[1:] if frame.startswith("/") else frame)
        o, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
        np.testing.assert_array_equal(block.orientation[k], [o.x, o.y, o.z, o.w])
        assert block.orientation_covariance0[k] == msg.orientation_covariance[0]
        np.testing.assert_array_equal(block.angular_velocity[k], [w.x, w.y, w.z])
        np.testing.assert_array_equal(block.linear_acceleration[k], [a.x, a.y, a.z])


def test_axes_are_the_per_message_decoders(messages: tuple[list[object], list[bytes]]) -> None:
    """Bit for bit: the recording of a block must be the recording of its messages one by one."""
    _, data = messages
    block = decode_imu_block(data, DecodeOptions())
    assert block is not None
    drawn, axes = block.axes()
    one_by_one = [decode(IMU, raw) for raw in data]
    arrows = [[i for i in d.items if isinstance(i, Arrows)] for d in one_by_one if isinstance(d, Decoded)]
    assert drawn.tolist() == [bool(a) for a in arrows]
    assert 0 < drawn.sum() < len(data) - len(ODD_Q)  # some are not drawn: odd quaternions, covariance[0] = -1
    np.testing.assert_array_equal(axes, np.array([a[0].vectors for a in arrows if a]))
    for k, d in enumerate(one_by_one):
        assert isinstance(d, Decoded)
        series = {i.name: i.values for i in d.items if isinstance(i, Series)}
        np.testing.assert_array_equal(series["angular_velocity"], block.angular_velocity[k])
        np.testing.assert_array_equal(series["linear_acceleration"], block.linear_acceleration[k])


def test_a_slice_is_those_rows(messages: tuple[list[object], list[bytes]]) -> None:
    block = decode_imu_block(messages[1], DecodeOptions())
    assert block is not None
    part = block.sliced(10, 20)
    assert len(part) == 10 and part.frames == block.frames
    np.testing.assert_array_equal(part.linear_acceleration, block.linear_acceleration[10:20])
    np.testing.assert_array_equal(part.frame_index, block.frame_index[10:20])


@pytest.mark.parametrize(
    "spoil",
    [
        lambda d: d[:-1],  # truncated
        lambda d: d + b"\0" * 8,  # longer than its layout
        lambda d: b"\x00\x02" + d[2:],  # an encapsulation it does not read (PL_CDR_BE)
        lambda d: d[:2] + b"\x00\x01" + d[4:],  # options set
        lambda d: d[:12] + (200).to_bytes(4, "little") + d[16:],  # a frame_id longer than the message
        lambda d: d[:12] + (0).to_bytes(4, "little") + d[16:],  # a string without even its NUL
        lambda d: d[:23] + b"x" + d[24:],  # "imu_lin" + 'x' where its NUL was
        lambda d: d[:16] + b"\xff" + d[17:],  # not UTF-8
        lambda d: d[:3],  # shorter than a header
    ],
)
def test_anything_odd_leaves_the_messages_to_the_per_message_decoder(spoil) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(1)
    good = [bytes(STORE.serialize_cdr(_imu(rng, "imu_lin"), IMU)) for _ in range(3)]
    assert decode_imu_block(good, DecodeOptions()) is not None
    assert decode_imu_block([good[0], spoil(good[1]), good[2]], DecodeOptions()) is None
