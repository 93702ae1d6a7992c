#!/usr/bin/env python3
"""Fleet conversion (issue 25): 12 bags, ``--jobs 2`` beside ``--jobs 1``, side by side in one run.

    python benchmarks/fleet.py                  # 12 bags of 15 min (R2D2 at 100 Hz, /tf at 50 Hz), 3 rounds
    python benchmarks/fleet.py --smoke          # 12 bags of 3 s, one round: a CI smoke run, no threshold
    python benchmarks/fleet.py --ray            # and a third column: --ray on a local Ray (two CPUs)

The bags are written here by ``rosbags`` (its serializer and writer; the tutorial's R2D2 as /robot_description,
/joint_states of its three joints, /tf odom → axis), each a little different. Each round runs the real CLI,
``r2d2-viz --bag B1 … B12 --save-dir DIR --jobs N --force``, in a subprocess, the job counts alternating; the
wall time is the whole command's (process starts and imports included), the CPU time the command's and its
workers' (``os.times`` of the children). Goal (issue 25): on 2 cores the median of ``--jobs 2`` ≤ 0.7 × the
median of ``--jobs 1``. The ratio is printed, not asserted: other work on the machine moves it (the load
average is printed at the start and the end; on a machine whose cores are already busy, two jobs cannot run
twice as fast).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

T0 = 1_700_000_000_000_000_000
BAGS = 12


def write_bags(folder: Path, seconds: float) -> list[Path]:
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    from r2d2_viz.robot.model import default_urdf_path

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    urdf = bytes(ts.serialize_cdr(T["std_msgs/msg/String"](default_urdf_path().read_text()), "std_msgs/msg/String"))

    def header(t: int, frame: str = "") -> object:
        return T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(int(t), 10**9)), frame)

    paths = []
    for b in range(BAGS):
        n = int(seconds * 100)
        k = np.arange(n)
        q = np.column_stack([np.sin(k * 0.01 + b), -0.25 - 0.2 * np.sin(k * 0.02), -0.2 + 0.1 * np.cos(k * 0.03)])
        path = folder / f"robot_{b:02d}"
        with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
            desc = writer.add_connection("/robot_description", "std_msgs/msg/String", typestore=ts)
            joints = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=ts)
            tf = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts)
            writer.write(desc, T0, urdf)
            for i in range(n):
                t = T0 + i * 10_000_000
                msg = T["sensor_msgs/msg/JointState"](
                    header(t), ["swivel", "tilt", "periscope"], q[i], np.zeros(0), np.zeros(0)
                )
                writer.write(joints, t, bytes(ts.serialize_cdr(msg, "sensor_msgs/msg/JointState")))
                if i % 2 == 0:
                    a = i * 0.001 + b
                    edge = T["geometry_msgs/msg/TransformStamped"](
                        header(t, "odom"),
                        "axis",
                        T["geometry_msgs/msg/Transform"](
                            T["geometry_msgs/msg/Vector3"](np.cos(a), np.sin(a), 0.0),
                            T["geometry_msgs/msg/Quaternion"](0.0, 0.0, np.sin(a / 2), np.cos(a / 2)),
                        ),
                    )
                    data = ts.serialize_cdr(T["tf2_msgs/msg/TFMessage"]([edge]), "tf2_msgs/msg/TFMessage")
                    writer.write(tf, t, bytes(data))
        paths.append(path)
    return paths


def convert(bags: list[Path], out: Path, how: list[str]) -> tuple[float, float]:
    """Wall seconds and CPU seconds (user + system, the command and its workers) of one conversion."""
    exe = Path(sys.executable).parent / "r2d2-viz"
    command = [str(exe), "--bag", *map(str, bags), "--save-dir", str(out), "--force", *how]
    before = os.times()
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = os.times()
    if result.returncode != 0:
        raise SystemExit(f"{' '.join(how)} failed: {result.stderr[-2000:]}")
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="12 bags of 3 s, one round (CI)")
    parser.add_argument("--seconds", type=float, default=900.0, help="length of each bag (default 900)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of each job count (default 3)")
    parser.add_argument("--ray", action="store_true", help="also --ray on a local Ray with two CPUs")
    args = parser.parse_args()
    seconds, rounds = (3.0, 1) if args.smoke else (args.seconds, args.rounds)
    columns = {"--jobs 1": ["--jobs", "1"], "--jobs 2": ["--jobs", "2"]}
    if args.ray:
        columns["--ray (local, 2 CPUs)"] = ["--ray", "--jobs", "2"]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        start = time.perf_counter()
        bags = write_bags(folder, seconds)
        size = sum(f.stat().st_size for b in bags for f in b.iterdir())
        print(f"{BAGS} bags of {seconds:g} s ({size / 1e6:.1f} MB) written in {time.perf_counter() - start:.1f} s")
        print(f"cores: {os.cpu_count()}; rounds: {rounds}")
        print(f"load average at the start: {os.getloadavg()[0]:.2f}")
        walls: dict[str, list[float]] = {name: [] for name in columns}
        cpus: dict[str, list[float]] = {name: [] for name in columns}
        for r in range(rounds):
            for name, how in columns.items():
                wall, cpu = convert(bags, folder / f"out_{r}_{len(walls[name])}_{how[-1]}", how)
                walls[name].append(wall)
                cpus[name].append(cpu)
                print(f"  round {r + 1}: {name}: {wall:.2f} s wall, {cpu:.2f} s CPU", flush=True)
        print(f"load average at the end: {os.getloadavg()[0]:.2f}")
    base = statistics.median(walls["--jobs 1"])
    print(f"\n{'command':<24}{'median wall (s)':>16}{'× --jobs 1':>12}{'median CPU (s)':>16}")
    for name, values in walls.items():
        median = statistics.median(values)
        print(f"{name:<24}{median:>16.2f}{median / base:>12.2f}{statistics.median(cpus[name]):>16.2f}")
    ratio = statistics.median(walls["--jobs 2"]) / base
    verdict = "smoke run, no goal" if args.smoke else ("goal met" if ratio <= 0.7 else "goal NOT met")
    print(f"\n--jobs 2 / --jobs 1 = {ratio:.2f} (goal ≤ 0.70: {verdict})")


if __name__ == "__main__":
    main()
