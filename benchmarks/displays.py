#!/usr/bin/env python3
"""Every display at the speed of the rest (issue 46, item 3): ``--save`` of a console bag and of a marker bag beside
rosbags' ``AnyReader`` read + deserialise of the same bag, in one run.

    python benchmarks/displays.py                       # the issue's two bags (120 s console, 10,000 MarkerArrays)
    python benchmarks/displays.py --data /work/bigdata  # keep the bags there (reused when present)
    python benchmarks/displays.py --smoke               # 5 s / 400 arrays, one round: CI, no thresholds

The bags are written by ``rosbags`` (its serializer and MCAP writer):

* **console**: the twenty custom-type topics of ``benchmarks/anymsg.py`` at 100 Hz, and beside them an IMU
  (``sensor_msgs/Imu``) at 100 Hz, odometry at 50 Hz, ``rcl_interfaces/Log`` at 20 Hz, a 4-status
  ``DiagnosticArray`` at 1 Hz, ``NavSatFix`` at 5 Hz and ``BatteryState`` at 1 Hz, with ``/tf_static``;
* **markers**: 10,000 ``MarkerArray`` s of 50 markers each (cubes, spheres, arrows, cylinders, lines, text; ids
  0–49 in two namespaces) at 100 Hz.

Each ``--save`` runs beside ``rosbags.highlevel.AnyReader`` + ``deserialize`` of every message (the documented
way to read a bag in Python), each a subprocess, alternating, medians of ``--rounds``: wall, CPU of the process
tree (user+sys by ``os.wait4``) and peak anonymous memory. Goal: ≤ 1.0× on both. Printed, never asserted.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from anymsg import ANYREADER, APP, PY, T0, TOPICS, _types, measured

S = 1_000_000_000
RATES = {  # display topic → (type, Hz)
    "/imu": ("sensor_msgs/msg/Imu", 100.0),
    "/odom": ("nav_msgs/msg/Odometry", 50.0),
    "/rosout": ("rcl_interfaces/msg/Log", 20.0),
    "/diagnostics": ("diagnostic_msgs/msg/DiagnosticArray", 1.0),
    "/fix": ("sensor_msgs/msg/NavSatFix", 5.0),
    "/battery": ("sensor_msgs/msg/BatteryState", 1.0),
}
MARKERS = 50
MARKER_KINDS = (0, 1, 2, 3, 4, 9)  # ARROW, CUBE, SPHERE, CYLINDER, LINE_STRIP, TEXT_VIEW_FACING


def _store() -> Any:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    for name, text in _types().items():
        ts.register(get_types_from_msg(text, name))
    return ts


def _header(T: Any, t: int, frame: str) -> Any:
    return T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(t, S)), frame)


def _display(T: Any, msgtype: str, t: int, i: int) -> Any:
    """The ``i``-th message of a display topic, at ``t``."""
    v3, q = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    a = 0.01 * i
    if msgtype == "sensor_msgs/msg/Imu":
        orientation = q(0.0, 0.0, math.sin(a / 2), math.cos(a / 2))
        z9 = np.zeros(9)
        return T[msgtype](_header(T, t, "imu_link"), orientation, z9, v3(0.1, -0.2, a), z9, v3(0.0, 0.5, 9.81), z9)
    if msgtype == "nav_msgs/msg/Odometry":
        pose = T["geometry_msgs/msg/Pose"](T["geometry_msgs/msg/Point"](0.02 * i, 0.0, 0.0), q(0.0, 0.0, 0.0, 1.0))
        twist = T["geometry_msgs/msg/Twist"](v3(1.0, 0.0, 0.0), v3(0.0, 0.0, 0.0))
        return T[msgtype](
            _header(T, t, "odom"),
            "base_link",
            T["geometry_msgs/msg/PoseWithCovariance"](pose, np.zeros(36)),
            T["geometry_msgs/msg/TwistWithCovariance"](twist, np.zeros(36)),
        )
    if msgtype == "rcl_interfaces/msg/Log":
        level = (10, 20, 30, 40)[i % 4]
        return T[msgtype](T["builtin_interfaces/msg/Time"](*divmod(t, S)), level, "node", f"tick {i}", "a.cpp", "f", i)
    if msgtype == "diagnostic_msgs/msg/DiagnosticArray":
        kv, status = T["diagnostic_msgs/msg/KeyValue"], T["diagnostic_msgs/msg/DiagnosticStatus"]
        items = [status(k % 3 if i % 2 else 0, f"motor {k}", "ok", "hw", [kv("current", str(i))]) for k in range(4)]
        return T[msgtype](_header(T, t, ""), items)
    if msgtype == "sensor_msgs/msg/NavSatFix":
        fix_status = T["sensor_msgs/msg/NavSatStatus"](0, 1)
        return T[msgtype](_header(T, t, "gps"), fix_status, 48.8 + 1e-6 * i, 2.29, 35.0, np.zeros(9), 0)
    cells = np.zeros(0, np.float32)
    values = (24.0 - 0.001 * i, 30.0, -3.0, 10.0, 20.0, 20.0, 0.8)
    return T[msgtype](_header(T, t, ""), *values, 2, 1, 2, True, cells, cells, "base", "SN1")


def write_console_bag(path: Path, seconds: float) -> int:
    """The console bag (MCAP, rosbags' writer: one file, in time order); returns the number of messages."""
    from anymsg import custom_message
    from rosbags.rosbag2 import StoragePlugin, Writer

    ts = _store()
    T = ts.types
    rng = np.random.default_rng(0)
    rows: list[tuple[int, str, str, int]] = []
    for topic, (msgtype, rate) in RATES.items():
        rows += [(T0 + int(i * S / rate) + 50, topic, msgtype, i) for i in range(int(seconds * rate))]
    rows.sort()
    count, j = 0, 0
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        tf_static = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        edges = [("odom", "base_link"), ("base_link", "imu_link"), ("base_link", "gps")]
        transform = T["geometry_msgs/msg/Transform"](
            T["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.1), T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0)
        )
        stamped = [T["geometry_msgs/msg/TransformStamped"](_header(T, T0, p), c, transform) for p, c in edges]
        writer.write(tf_static, T0, bytes(ts.serialize_cdr(T["tf2_msgs/msg/TFMessage"](stamped), tf_static.msgtype)))
        custom = [
            writer.add_connection(f"/robot/sensor{k:02d}", f"bench_msgs/msg/Sensor{k:02d}", typestore=ts)
            for k in range(TOPICS)
        ]
        displays = {topic: writer.add_connection(topic, msgtype, typestore=ts) for topic, (msgtype, _) in RATES.items()}
        for i in range(int(seconds * 100)):
            t = T0 + i * S // 100
            for k, connection in enumerate(custom):
                writer.write(
                    connection, t + k, bytes(ts.serialize_cdr(custom_message(T, k, i, t, rng), connection.msgtype))
                )
            while j < len(rows) and rows[j][0] < t + S // 100:
                t_msg, topic, msgtype, n = rows[j]
                writer.write(displays[topic], t_msg, bytes(ts.serialize_cdr(_display(T, msgtype, t_msg, n), msgtype)))
                j += 1
            count += TOPICS
    return count + j + 1


def _marker(T: Any, k: int, i: int) -> Any:
    kind = MARKER_KINDS[k % len(MARKER_KINDS)]
    pt, q = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
    pose = T["geometry_msgs/msg/Pose"](pt(0.1 * k, 0.01 * (i % 100), 0.0), q(0.0, 0.0, 0.0, 1.0))
    points = [pt(0.0, 0.0, 0.0), pt(0.5, 0.0, 0.0), pt(0.5, 0.5, 0.0)] if kind == 4 else []
    return T["visualization_msgs/msg/Marker"](
        header=_header(T, T0, "base_link"),
        ns="objects" if k % 2 else "tracks",
        id=k,
        type=kind,
        action=0,
        pose=pose,
        scale=T["geometry_msgs/msg/Vector3"](0.2, 0.05, 0.05)
        if kind == 0
        else T["geometry_msgs/msg/Vector3"](0.1, 0.1, 0.1),
        color=T["std_msgs/msg/ColorRGBA"](0.2, 0.4, 1.0, 1.0),
        lifetime=T["builtin_interfaces/msg/Duration"](0, 0),
        frame_locked=False,
        points=points,
        colors=[],
        texture_resource="",
        texture=T["sensor_msgs/msg/CompressedImage"](_header(T, 0, ""), "", np.zeros(0, np.uint8)),
        uv_coordinates=[],
        text=f"object {k}" if kind == 9 else "",
        mesh_resource="",
        mesh_file=T["visualization_msgs/msg/MeshFile"]("", np.zeros(0, np.uint8)),
        mesh_use_embedded_materials=False,
    )


def write_marker_bag(path: Path, arrays: int) -> int:
    """``arrays`` MarkerArrays of :data:`MARKERS` markers at 100 Hz in ``base_link`` (MCAP, rosbags' writer, the
    Jazzy store: its Marker has the texture and mesh-file fields), with ``/tf_static`` odom → base_link."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_JAZZY)
    T = ts.types
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        tf_static = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        transform = T["geometry_msgs/msg/Transform"](
            T["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.0), T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0)
        )
        edge = T["geometry_msgs/msg/TransformStamped"](_header(T, T0, "odom"), "base_link", transform)
        writer.write(tf_static, T0, bytes(ts.serialize_cdr(T["tf2_msgs/msg/TFMessage"]([edge]), tf_static.msgtype)))
        connection = writer.add_connection("/markers", "visualization_msgs/msg/MarkerArray", typestore=ts)
        for i in range(arrays):
            msg = T["visualization_msgs/msg/MarkerArray"]([_marker(T, k, i) for k in range(MARKERS)])
            writer.write(connection, T0 + i * S // 100 + 1, bytes(ts.serialize_cdr(msg, connection.msgtype)))
    return arrays + 1


def side_by_side(name: str, bag: Path, out: Path, rounds: int, smoke: bool) -> dict[str, float]:
    """``--save`` of ``bag`` beside AnyReader on the same files, alternating; medians printed with their ratio."""
    ours = [APP, "--bag", str(bag), "--save", str(out)]
    theirs = [PY, "-c", ANYREADER, str(bag)]
    got: dict[str, list[tuple[float, float, float]]] = {"ours": [], "theirs": []}
    loads = []
    for _ in range(rounds):
        for key, command in (("ours", ours), ("theirs", theirs)):
            if key == "ours":
                out.unlink(missing_ok=True)  # outputs deleted first
            loads.append(os.getloadavg()[0])
            got[key].append(measured(command))
    med = {k: tuple(statistics.median(r[j] for r in runs) for j in range(3)) for k, runs in got.items()}
    print(f"{name}: medians of {rounds} alternating (load {min(loads):.1f}–{max(loads):.1f}):")
    for key, label in (("ours", "r2d2-viz --save"), ("theirs", "rosbags AnyReader + deserialize")):
        wall, cpu, peak = med[key]
        print(f"  {label:32s} wall {wall:5.2f} s  CPU {cpu:5.2f} s  peak {peak:4.0f} MB")
    wall, cpu = med["ours"][0] / med["theirs"][0], med["ours"][1] / med["theirs"][1]
    goal = "" if smoke else (" met" if wall <= 1.0 else " NOT met")
    print(f"  ratio: wall {wall:.2f}x, CPU {cpu:.2f}x (goal ≤ 1.0x wall){goal}")
    print(f"  the recording: {out.stat().st_size / 1e6:.1f} MB")
    return {"wall": wall, "cpu": cpu}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="seconds of console bag (default 120)")
    parser.add_argument("--arrays", type=int, default=10_000, help="MarkerArrays in the marker bag (default 10,000)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--data", type=Path, default=None, help="keep the bags in this folder (reused when present)")
    parser.add_argument("--only", choices=("console", "markers"), default=None)
    parser.add_argument("--smoke", action="store_true", help="5 s / 400 arrays, one round, no thresholds")
    args = parser.parse_args()
    if args.smoke:
        args.seconds, args.arrays, args.rounds = 5.0, 400, 1
    tmp = Path(tempfile.mkdtemp(prefix="displays-"))
    try:
        folder = args.data if args.data is not None else tmp
        console = folder / f"console_{args.seconds:g}s"
        markers = folder / f"markers_{args.arrays}"
        if args.only != "markers":
            if not console.exists():
                t = time.perf_counter()
                n = write_console_bag(console, args.seconds)
                print(f"wrote {console}: {n:,} messages in {time.perf_counter() - t:.0f} s", file=sys.stderr)
            print(f"console bag: {TOPICS} custom topics at 100 Hz + {', '.join(RATES)}; {args.seconds:g} s")
            side_by_side("console", console, tmp / "c.rrd", args.rounds, args.smoke)
        if args.only != "console":
            if not markers.exists():
                t = time.perf_counter()
                n = write_marker_bag(markers, args.arrays)
                print(f"wrote {markers}: {n:,} messages in {time.perf_counter() - t:.0f} s", file=sys.stderr)
            print(f"marker bag: {args.arrays:,} MarkerArrays of {MARKERS} markers at 100 Hz")
            side_by_side("markers", markers, tmp / "m.rrd", args.rounds, args.smoke)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
