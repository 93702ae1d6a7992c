"""Blocks of Imu messages as columns (issue 46): the recording of a batch run that decodes each window's Imu messages
as one block is the recording of the same run decoding them one by one (every entity, time and value), on a bag
written by rosbags (random values, two byte orders, frame ids with and without a leading '/', orientations not
drawn); a window holding a malformed message, and a topic of empty frame ids, go one by one with their warnings.

One bag, two real CLI runs (module-scoped): block decoders on (counted), and off (``BLOCK_DECODERS`` emptied: the
per-message path)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from rrd import read_recording

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types
S, T0 = 1_000_000_000, 1_700_000_000 * 1_000_000_000
IMU, LOG = "sensor_msgs/msg/Imu", "rcl_interfaces/msg/Log"
RUN = """
import atexit, sys
from r2d2_viz.msgs import registry
rows = []
if sys.argv[1] == "off":
    registry.BLOCK_DECODERS.clear()
else:
    decoder = registry.BLOCK_DECODERS["sensor_msgs/msg/Imu"]
    def counted(messages, options):
        block = decoder(messages, options)
        rows.append(0 if block is None else len(block))
        return block
    registry.BLOCK_DECODERS["sensor_msgs/msg/Imu"] = counted
    atexit.register(lambda: print("block rows", sum(rows), "pyarrow.compute" in sys.modules, file=sys.stderr))
from r2d2_viz.cli.command import main
sys.exit(main(sys.argv[2:]))
"""


def _imu(rng: np.random.Generator, t_ns: int, frame: str, q: Any = None) -> Any:
    v3, quat = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(t_ns - 3_000_000, S)), frame)
    cov = rng.normal(size=9)
    if q is None and rng.random() < 0.1:
        cov[0] = -1.0  # no orientation
    return T[IMU](
        header,
        quat(*(rng.normal(size=4) if q is None else q)),
        cov,
        v3(*rng.normal(size=3)),
        cov,
        v3(*rng.normal(size=3)),
        cov,
    )


def _tf() -> Any:
    tr = T["geometry_msgs/msg/Transform"](
        T["geometry_msgs/msg/Vector3"](1.0, 0, 0), T["geometry_msgs/msg/Quaternion"](0, 0, 0, 1.0)
    )
    header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(T0, S)), "odom")
    edges = [T["geometry_msgs/msg/TransformStamped"](header, child, tr) for child in ("imu_link", "base_imu")]
    return T["tf2_msgs/msg/TFMessage"](edges)


def write_bag(path: Path) -> Path:
    """/imu: 300 messages at 100 Hz (two frames, one written with a leading '/', every third big-endian, odd
    orientations); /imu_bad: 40, the 20th cut short; /imu_bare: 10 with an empty frame id; /rosout between."""
    rng = np.random.default_rng(46)
    odd = [(0.0, 0.0, 0.0, 0.0), (math.nan, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 1e-12)]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        tf = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=STORE)
        writer.write(tf, T0, bytes(STORE.serialize_cdr(_tf(), "tf2_msgs/msg/TFMessage")))
        imu, bad, bare = (writer.add_connection(t, IMU, typestore=STORE) for t in ("/imu", "/imu_bad", "/imu_bare"))
        log = writer.add_connection("/rosout", LOG, typestore=STORE)
        for k in range(300):
            t = T0 + k * S // 100
            frame = ("imu_link", "/imu_link", "base_imu")[k % 3]
            msg = _imu(rng, t, frame, odd[k // 7 % 3] if k % 7 == 0 else None)
            writer.write(imu, t, bytes(STORE.serialize_cdr(msg, IMU, little_endian=k % 3 != 1)))
            if k % 7 == 3 and k < 280:
                data = bytes(STORE.serialize_cdr(_imu(rng, t + 1, "imu_link"), IMU))
                writer.write(bad, t + 1, data[:-5] if k == 3 + 7 * 20 else data)
            if k % 30 == 5:
                writer.write(bare, t + 2, bytes(STORE.serialize_cdr(_imu(rng, t + 2, ""), IMU)))
                stamp = T["builtin_interfaces/msg/Time"](*divmod(t, S))
                line = T[LOG](stamp, 20, "imu_node", f"tick {k}", "imu.cpp", "spin", k)
                writer.write(log, t + 2, bytes(STORE.serialize_cdr(line, LOG)))
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, subprocess.CompletedProcess[str]]]:
    folder = tmp_path_factory.mktemp("imu_blocks")
    bag = write_bag(folder / "imu_bag")
    out: dict[str, tuple[Path, subprocess.CompletedProcess[str]]] = {}
    for name, mode in (("blocks", "on"), ("messages", "off")):
        rrd = folder / f"{name}.rrd"
        args = [sys.executable, "-c", RUN, mode, "--bag", str(bag), "--save", str(rrd)]
        done = subprocess.run(args, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        out[name] = (rrd, done)
    return out


def _said(done: subprocess.CompletedProcess[str]) -> list[str]:
    return [line.split(" to ")[0] for line in done.stderr.splitlines() if not line.startswith("block rows")]


def test_the_block_path_was_taken(runs: dict[str, tuple[Path, subprocess.CompletedProcess[str]]]) -> None:
    said = runs["blocks"][1].stderr
    rows = int(said.split("block rows ")[1].split()[0])
    assert rows == 300 + 10  # /imu's messages, and /imu_bare's (decoded, then left to the one-by-one path)
    assert said.split("block rows ")[1].split()[1] == "False"  # no pyarrow.compute (~0.5 s to import: Array.take)
    assert "/imu_bad: a sensor_msgs/msg/Imu message cannot be shown" in said


def test_the_recording_is_the_per_message_one(runs: dict[str, tuple[Path, subprocess.CompletedProcess[str]]]) -> None:
    blocks, messages = read_recording(runs["blocks"][0]), read_recording(runs["messages"][0])
    assert set(blocks) == set(messages)
    assert len(blocks["/imu/angular_velocity"].times) == 300 and len(blocks["/imu_bad/linear_acceleration"].times) == 39
    assert 200 < len(blocks["/imu"].times) < 300  # axes: not for the odd orientations
    for entity in sorted(set(blocks) - {"/__properties"}):
        a, b = blocks[entity], messages[entity]
        assert a.times == b.times, entity
        assert dict(a.temporal) == dict(b.temporal), entity
        assert dict(a.static) == dict(b.static), entity
    assert _said(runs["blocks"][1]) == _said(runs["messages"][1])  # the same warnings (the empty frame ids…)
