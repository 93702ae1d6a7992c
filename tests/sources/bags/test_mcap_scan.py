"""Scanning an MCAP file: what it finds must be what rosbags reads from it, and from a damaged one a prefix of that."""

from __future__ import annotations

import os
from pathlib import Path

from bagmaker import T0, BagSpec, joint_state, storage_file, string, write_bag
from rosbags.rosbag2 import Reader

from r2d2_viz.sources.bags.mcap_scan import McapScan


def _intact(tmp_path: Path, n: int = 5000) -> Path:
    """rosbags' writer makes chunks of about 1 MB: 20,000 of these messages fill two."""
    spec = BagSpec().add("/robot_description", T0, string("<robot/>"))
    for k in range(n):
        spec.add("/joint_states", T0 + k, joint_state(T0 + k, ["a", "b"], [k, -k]))
    return storage_file(write_bag(tmp_path / "b", spec))


def test_an_intact_file_scans_like_rosbags_reads_it(tmp_path: Path) -> None:
    file = _intact(tmp_path)
    scan = McapScan(file)
    assert scan.topics() == {
        "/robot_description": ("std_msgs/msg/String", 1),
        "/joint_states": ("sensor_msgs/msg/JointState", 5000),
    }
    with Reader(file) as reader:
        expected = [(t, bytes(d)) for c, t, d in reader.messages() if c.topic == "/joint_states"]
    assert [(t, bytes(d)) for t, d in scan.messages("/joint_states")] == expected


def test_a_cut_file_gives_a_prefix(tmp_path: Path) -> None:
    file = _intact(tmp_path, 20000)
    with Reader(file) as reader:
        expected = [(t, bytes(d)) for c, t, d in reader.messages() if c.topic == "/joint_states"]
    data = file.read_bytes()
    for fraction in (0.6, 0.95):
        cut = tmp_path / f"cut{fraction}.mcap"
        cut.write_bytes(data[: int(len(data) * fraction)])
        got = [(t, bytes(d)) for t, d in McapScan(cut).messages("/joint_states")]
        assert 0 < len(got) <= len(expected) and got == expected[: len(got)]
        assert fraction > 0.9 or len(got) < len(expected)  # the last 10 % are indexes and the summary


def test_junk_gives_nothing(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(os.urandom(2000))
    assert McapScan(junk).topics() == {}
    huge = tmp_path / "huge.mcap"  # a record claiming 2**63 bytes
    huge.write_bytes(b"\x89MCAP0\r\n" + b"\x06" + b"\xff" * 8 + b"\x00" * 50)
    assert McapScan(huge).topics() == {}
