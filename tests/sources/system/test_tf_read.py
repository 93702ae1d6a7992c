"""Reading a bag for the TF tree: the header frames and stamps gathered from CDR bytes with numpy agree with
rosbags' deserialiser, message by message, on crafted bags and on a real one."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from tfbags import MS, T0, TS, bag, edge_every, point, real_bag, spec

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.system.tf_read import bag_tree, has_header, read_bag


def reference_headers(path: Path) -> list[tuple[str, str, int, int]]:
    """``(topic, frame, stamp, receive)`` of every message with a header, by rosbags (leading '/' dropped)."""
    out = []
    with AnyReader([path], default_typestore=TS) as reader:
        conns = [c for c in reader.connections if c.topic not in ("/tf", "/tf_static") and c.msgtype in TS.fielddefs]
        for conn, t, data in reader.messages(connections=conns):
            msg = reader.deserialize(data, conn.msgtype)
            header = getattr(msg, "header", None)
            if header is not None and type(header).__name__ == "std_msgs__msg__Header":
                stamp = header.stamp.sec * 1_000_000_000 + header.stamp.nanosec
                out.append((conn.topic, header.frame_id.removeprefix("/"), stamp, t))
    return sorted(out)


def ours(path: Path) -> list[tuple[str, str, int, int]]:
    with open_bag(path) as b:
        _, _, h = read_bag(b)
    return sorted(
        (h.topics[int(i)], str(f), int(s), int(r))
        for i, f, s, r in zip(h.topic_index, h.frames, h.stamps_ns, h.receive_ns, strict=True)
    )


def test_which_types_start_with_a_header() -> None:
    assert has_header("sensor_msgs/msg/LaserScan") and has_header("geometry_msgs/msg/PointStamped")
    assert not has_header("std_msgs/msg/String") and not has_header("tf2_msgs/msg/TFMessage")
    assert not has_header("geometry_msgs/msg/Point") and not has_header("no_pkg/msg/Nothing")


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_header_frames_and_stamps_agree_with_rosbags(tmp_path: Path, storage: str) -> None:
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(5) * 100 * MS)
    for k, frame in enumerate(["camera", "", "/odom", "a_long_frame_name_" * 10, "é"]):
        s.add("/points", T0 + k * 7 * MS, point(T0 - k * 3 * MS, frame))
    path = bag(tmp_path / "b", s, storage)
    expected = reference_headers(path)
    assert len(expected) == 5 and ours(path) == expected


def test_header_frames_of_a_real_bag_agree_with_rosbags() -> None:
    path = real_bag("webots_epuck")
    expected = reference_headers(path)
    assert len(expected) > 10_000 and ours(path) == expected


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_vendors_header_type_and_big_endian_headers(tmp_path: Path, storage: str) -> None:
    """Header-first by the bag's own definition (a vendor's type Humble does not have) and headers read in their
    CDR's endianness (a big-endian PointStamped): every frame and stamp as rosbags deserialises them (with the
    bag's definitions), and both unreached frames named."""
    from headerbags import write

    path = write(tmp_path / "b", storage)
    expected = []
    with AnyReader([path]) as reader:
        assert reader.connections and all(c.msgtype in reader.typestore.fielddefs for c in reader.connections)
        for conn, t, data in reader.messages([c for c in reader.connections if c.topic != "/tf"]):
            h = reader.deserialize(data, conn.msgtype).header
            expected.append((conn.topic, h.frame_id, h.stamp.sec * 1_000_000_000 + h.stamp.nanosec, t))
    assert len(expected) == 100 and ours(path) == sorted(expected)
    with open_bag(path) as b:
        tree = bag_tree(b)
    assert tree.problems == (
        "frame camera: named in the headers of /points_be; no transform reaches it",
        "frame sensor: named in the headers of /reading; no transform reaches it",
    )
