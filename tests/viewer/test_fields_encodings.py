"""Issue 37's findings 3 and 6 on the generic fields, as found: big-endian CDR of a topic no display draws was
skipped, ROS 1's ``byte`` -5 showed as 251, and a message whose length disagrees with its definition (a definition
that changed between the files of one bag) was shown with wrong values. Bags written by rosbags, the CLI in a
subprocess, the recording read back; golden values from rosbags' deserializer."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import cli
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rrd import read_recording

T0 = 1_700_000_000_000_000_000
BATTERY = "lab_msgs/msg/Battery"


def _fields(rows: Any, msgtype: str, at: int) -> dict[str, Any]:
    return {n.split(":", 1)[1]: v[at][0] for n, v in rows.temporal.items() if n.startswith(msgtype + ":") and v[at]}


def test_big_endian_messages_of_a_generic_topic_are_decoded(tmp_path: Path) -> None:
    ts = get_typestore(Stores.ROS2_HUMBLE)
    ts.register(get_types_from_msg("float32 voltage\nint16[] cells\nstring chemistry\nfloat64 current\n", BATTERY))
    T = ts.types
    msgs = [T[BATTERY](12.5 + k, np.array([-3, 300 + k], dtype=np.int16), "LiPo", -1.25 * k) for k in range(4)]
    with Writer(tmp_path / "bag", version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/battery", BATTERY, typestore=ts)
        written = []
        for k, msg in enumerate(msgs):
            data = bytes(ts.serialize_cdr(msg, BATTERY, little_endian=k % 2 == 0))  # every other one big-endian
            writer.write(conn, T0 + k * 10**8, data)
            written.append((T0 + k * 10**8, data))
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(tmp_path / "bag"), "--save", str(out), "--plot", "/battery.cells[1]", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "skipped" not in result.stderr, result.stderr
    recording = read_recording(out)
    rows = recording["/topics/battery"]
    assert rows.times == [t for t, _ in written]
    for at, (_, data) in enumerate(written):
        want = ts.deserialize_cdr(data, BATTERY)
        got = _fields(rows, BATTERY, at)
        assert got["voltage"] == pytest.approx(want.voltage)
        assert got["current"] == want.current
        assert [got["cells[0]"], got["cells[1]"]] == want.cells.tolist()
        assert got["chemistry"] == want.chemistry
    [series] = [r for e, r in recording.items() if e.startswith("/plot/0/")]
    want_cells = [float(ts.deserialize_cdr(d, BATTERY).cells[1]) for _, d in written]
    assert [v[0] for v in series.temporal["Scalars:scalars"]] == want_cells


def test_a_ros1_byte_is_signed(tmp_path: Path) -> None:
    ts = get_typestore(Stores.ROS1_NOETIC)
    msgtype = "lab_msgs/msg/Bump"
    ts.register(get_types_from_msg("byte level\nchar letter\nbyte[3] levels\nint8 other\n", msgtype))
    T = ts.types
    path = tmp_path / "bumps.bag"
    written = []
    with Writer1(path) as writer:
        conn = writer.add_connection("/bump", msgtype, typestore=ts)
        for k in range(3):
            msg = T[msgtype](-5 - k, 200, np.array([-1, 2, -128], dtype=np.int8), -7)
            data = bytes(ts.serialize_ros1(msg, msgtype))
            writer.write(conn, T0 + k * 10**8, data)
            written.append(data)
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(path), "--save", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    rows = read_recording(out)["/topics/bump"]
    for at, data in enumerate(written):
        want = ts.deserialize_ros1(data, msgtype)  # rosbags: byte is int8 in ROS 1 (-5), char uint8
        got = _fields(rows, msgtype, at)
        assert got["level"] == want.level < 0
        assert got["letter"] == want.letter == 200
        assert [got[f"levels[{i}]"] for i in range(3)] == want.levels.tolist()


def test_a_message_longer_than_its_definition_is_counted_never_shown(tmp_path: Path) -> None:
    """The bag's definition says one float; the messages carry two (their type changed): rosbags says "size
    mismatch"; the app showed the first float as if all was well."""
    ts = get_typestore(Stores.ROS2_HUMBLE)
    ts.register(get_types_from_msg("float32 voltage\nfloat32 current\n", BATTERY))
    old = "float32 voltage\n"
    with Writer(tmp_path / "bag", version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/battery", BATTERY, msgdef=old, rihs01="RIHS01_" + "0" * 64)
        for k in range(5):
            data = bytes(ts.serialize_cdr(ts.types[BATTERY](23.0, 1.5), BATTERY))
            writer.write(conn, T0 + k * 10**8, data)
    check = get_typestore(Stores.ROS2_HUMBLE)
    check.register(get_types_from_msg(old, BATTERY))
    with pytest.raises(Exception, match="size mismatch"):  # the golden verdict: rosbags with the bag's definition
        check.deserialize_cdr(data, BATTERY)
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(tmp_path / "bag"), "--save", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "/topics/battery" not in read_recording(out)
    lines = [line for line in result.stderr.splitlines() if "/battery" in line and "size mismatch" in line]
    assert len(lines) == 1 and "5 messages" in lines[0], result.stderr


def test_each_file_of_a_bag_is_decoded_with_its_own_definition(tmp_path: Path) -> None:
    """A type that gained a field between two recordings of one (split) bag was read with the first file's
    definition: voltage 8.4e-45 instead of 23.0, current = the real voltage."""
    definitions = ("float32 voltage\nfloat32 current\n", "uint32 cells\nfloat32 voltage\nfloat32 current\n")
    bag = tmp_path / "bag"
    bag.mkdir()
    written = []
    for k, text in enumerate(definitions):
        ts = get_typestore(Stores.ROS2_HUMBLE)
        ts.register(get_types_from_msg(text, BATTERY))
        part = tmp_path / f"part{k}"
        with Writer(part, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
            conn = writer.add_connection("/battery", BATTERY, typestore=ts)
            for i in range(4):
                values = (23.0 + i, 1.5 * i) if k == 0 else (6, 23.0 + i, 1.5 * i)
                data = bytes(ts.serialize_cdr(ts.types[BATTERY](*values), BATTERY))
                t = T0 + (k * 10 + i) * 10**8
                writer.write(conn, t, data)
                written.append((t, ts.deserialize_cdr(data, BATTERY)))  # golden: rosbags, with this file's definition
        [mcap] = part.glob("*.mcap")
        mcap.rename(bag / f"bag_{k}.mcap")
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "skipped" not in result.stderr, result.stderr
    rows = read_recording(out)["/topics/battery"]
    assert rows.times == [t for t, _ in written]
    for at, (_, want) in enumerate(written):
        got = _fields(rows, BATTERY, at)
        assert got["voltage"] == pytest.approx(want.voltage) and got["current"] == pytest.approx(want.current)
        assert ("cells" in got) == hasattr(want, "cells"), got  # the older messages have no cells (cleared)
