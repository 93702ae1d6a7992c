"""The record layer of ROS 1 bags: names as rosbag2 gives them, record headers, chunks of each compression, and
lengths that are checked against the bytes there are before anything is read or allocated."""

from __future__ import annotations

import bz2
import io
import struct

import lz4.frame
import pytest

from r2d2_viz.sources.bags.rosbag1_records import (
    BrokenError,
    RecordFile,
    chunk_records,
    decompress,
    fields,
    ros2_type,
    time_ns,
    topic_name,
)


def _field(name: bytes, value: bytes) -> bytes:
    return struct.pack("<I", len(name) + 1 + len(value)) + name + b"=" + value


def _record(header: bytes, data: bytes) -> bytes:
    return struct.pack("<I", len(header)) + header + struct.pack("<I", len(data)) + data


def test_names() -> None:
    assert topic_name("joint_states") == "/joint_states"
    assert topic_name("//robot//tf") == "/robot/tf"
    assert ros2_type("sensor_msgs/JointState") == "sensor_msgs/msg/JointState"
    assert ros2_type("tf/tfMessage") == "tf2_msgs/msg/TFMessage"
    assert ros2_type("pkg/msg/Already") == "pkg/msg/Already"


def test_header_fields_and_times() -> None:
    header = _field(b"op", b"\x02") + _field(b"conn", struct.pack("<I", 7)) + _field(b"time", struct.pack("<II", 3, 4))
    got = fields(header, 0, len(header))
    assert got == {b"op": b"\x02", b"conn": struct.pack("<I", 7), b"time": struct.pack("<II", 3, 4)}
    assert time_ns(got[b"time"]) == 3_000_000_004
    with pytest.raises(BrokenError):
        fields(header, 0, len(header) - 1)  # a field cut short
    with pytest.raises(BrokenError):
        fields(struct.pack("<I", 3) + b"abc", 0, 7)  # no '='


def test_chunks_of_each_compression() -> None:
    raw = b"".join(_record(_field(b"op", b"\x02"), bytes([k]) * k) for k in range(1, 6))
    assert decompress(b"none", raw, len(raw)) == raw
    assert decompress(b"bz2", bz2.compress(raw), len(raw)) == raw
    assert decompress(b"lz4", lz4.frame.compress(raw), len(raw)) == raw
    assert len(decompress(b"bz2", bz2.compress(bytes(10**6)), 1000)) == 1000  # never more than the header says
    with pytest.raises(ValueError, match="zstd"):
        decompress(b"zstd", raw, len(raw))
    assert [buf_end - start for _, start, buf_end in chunk_records(raw)] == [1, 2, 3, 4, 5]
    assert len(list(chunk_records(raw[:-2]))) == 4  # the records up to the one cut short


def test_lengths_beyond_the_file_are_refused_before_reading() -> None:
    huge = struct.pack("<I", 0xFFFFFFF0) + b"x" * 20
    records = RecordFile(io.BytesIO(huge), len(huge))
    with pytest.raises(BrokenError):
        records.read(0)
    good = _record(_field(b"op", b"\x07"), b"")
    lying = good[:-4] + struct.pack("<I", 1 << 31)  # data length far beyond the end
    with pytest.raises(BrokenError):
        RecordFile(io.BytesIO(lying), len(lying)).read(0)
    header, data, start, end = RecordFile(io.BytesIO(good), len(good)).read(0)
    assert (header, data, end) == ({b"op": b"\x07"}, b"", len(good)) and start == end
