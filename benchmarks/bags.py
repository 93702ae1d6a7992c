#!/usr/bin/env python3
"""Reading ROS 2 bags (issue 11, part 9): our decoding of ``/joint_states`` beside the alternatives, and memory.

    python benchmarks/bags.py                 # 1 h at 100 Hz (8 joints); 1 h at 1 kHz (30 joints) for memory
    python benchmarks/bags.py --smoke         # 2 min and 1 min: a CI smoke run, no thresholds
    python benchmarks/bags.py --minutes 10 --big-minutes 10

The bags are written inside the benchmark by ``rosbags`` (its writer; the 100 Hz bag's messages by its
serializer, the 1 kHz bag's from one message it serialized, with stamps and positions patched in), in both
storages. Each reader runs in its own subprocess (``os.wait4`` gives wall time and peak RSS); the decode time
is what the child measures around the decoding alone, after its imports. Side by side on the same files:

* ours: the one pass (``BagPass``, joint states only) to arrays (times (n,), positions (n, 8));
* rosbags: its reader and ``deserialize_cdr`` per message, to the same arrays;
* Rerun's ``rerun.chunk.McapReader`` (``ros2msg`` decoder, Rust) to the same arrays (.mcap only);
* ``rerun mcap convert`` (the CLI of rerun-sdk) from .mcap to .rrd: plots only, no robot.

Whole commands (the issue's goals): ``r2d2-viz --bag BAG --urdf arm8.urdf --save out.rrd`` (an 8-joint chain
of boxes, written here) beside the import floor (a Python that imports what the app imports, nothing else) and
``rerun mcap convert`` of the same bag, medians of three runs alternating; the work beyond the floor over
Rerun's converter's whole wall time (goals: ≤ 1.5× for .mcap, ≤ 3× for .db3). And the peak RSS of
``r2d2-viz --bag`` on the 1 kHz, 30-joint bag (goal: under 400 MB).

Memory: peak RSS of a child reading the 1 kHz, 30-joint bag window by window through ``BagPass`` (goal:
under 400 MB), beside the RSS of the same child's imports alone.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

PY = sys.executable
T0 = 1_700_000_000_000_000_000


def _rerun() -> str | None:
    exe = Path(PY).parent / "rerun"
    return str(exe) if exe.exists() else shutil.which("rerun")


def _run(command: list[str]) -> tuple[float, float, str]:
    """Wall seconds, peak RSS in MB, stdout of a child."""
    start = time.perf_counter()
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    out = proc.stdout.read() if proc.stdout else ""
    err = proc.stderr.read() if proc.stderr else ""
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{command[:3]} failed: {err[-2000:]}")
    return wall, usage.ru_maxrss / 1024, out


HWM = """
def HWM():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
"""


def _child(code: str, *args: str) -> tuple[float, float, str]:
    """Wall seconds, the child's own peak RSS (VmHWM: its address space only, not the parent's pages it
    had before exec, which ``ru_maxrss`` would count), and its output."""
    wall, _, out = _run([PY, "-c", HWM + textwrap.dedent(code), *args])
    return wall, float(out.split()[-1]), out


LAUNCH = "import os, subprocess, sys; p = subprocess.Popen(sys.argv[1:]); print(os.wait4(p.pid, 0)[2].ru_maxrss / 1024)"


def _command(command: list[str]) -> tuple[float, float]:
    """Wall seconds and peak RSS of a command, started from a small launcher (so its pre-exec pages are few)."""
    wall, _, out = _run([PY, "-c", LAUNCH, *command])
    return wall, float(out.split()[-1])


OURS = """
    import sys, time
    import numpy as np
    from r2d2_viz.sources.bags.bag import open_bag
    from r2d2_viz.sources.playback import BagPass, Segment
    t = time.perf_counter()
    with open_bag(sys.argv[1]) as bag:
        joints = [f"joint_{i}" for i in range(int(sys.argv[2]))]
        one_pass = BagPass(bag, [Segment(("/joint_states",))], actuated=joints, displays={})
        chunks = [w.joints for w in one_pass.windows(10_000) if w.joints is not None]
    times = np.concatenate([c.times_ns for c in chunks]); pos = np.vstack([c.positions for c in chunks])
    print(time.perf_counter() - t, len(times), float(np.nansum(pos)), HWM())
"""

ROSBAGS = """
    import sys, time
    import numpy as np
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    t = time.perf_counter()
    times, rows = [], []
    with Reader(sys.argv[1]) as reader:
        for _, stamp, data in reader.messages():
            msg = ts.deserialize_cdr(data, "sensor_msgs/msg/JointState")
            times.append(stamp); rows.append(msg.position)
    times = np.asarray(times, dtype=np.int64); pos = np.vstack(rows)
    print(time.perf_counter() - t, len(times), float(np.nansum(pos)), HWM())
"""

RERUN_READER = """
    import sys, time
    import numpy as np
    import pyarrow as pa
    import pyarrow.compute as pc
    from rerun.chunk import McapReader
    t = time.perf_counter()
    times, values = [], []
    for chunk in McapReader(sys.argv[1], decoders=["ros2msg"], include_topic_regex=["^/joint_states$"]).stream():
        if chunk.entity_path != "/joint_states/position":
            continue
        batch = chunk.to_record_batch()
        times.append(batch.column("message_log_time").cast(pa.int64()).to_numpy())
        values.append(pc.list_flatten(batch.column("Scalars:scalars")).to_numpy())
    times = np.concatenate(times); pos = np.concatenate(values).reshape(len(times), -1)
    print(time.perf_counter() - t, len(times), float(np.nansum(pos)), HWM())
"""

MEMORY = """
    import sys, time
    from r2d2_viz.sources.bags.bag import open_bag
    from r2d2_viz.sources.playback import BagPass, Segment
    if sys.argv[2] == "0":
        print(0, 0, 0.0, HWM()); raise SystemExit
    t, n = time.perf_counter(), 0
    with open_bag(sys.argv[1]) as bag:
        one_pass = BagPass(bag, [Segment(("/joint_states",))], actuated=[f"joint_{i}" for i in range(30)], displays={})
        for window in one_pass.windows(10_000):
            n += len(window.joints) if window.joints is not None else 0
    print(time.perf_counter() - t, n, 0.0, HWM())
"""


def write_arm_bags(folder: Path, minutes: float) -> dict[str, Path]:
    """100 Hz, 8 joints, every message serialized by rosbags; the same messages in both storages."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    n = int(minutes * 60 * 100)
    names = [f"joint_{i}" for i in range(8)]
    k = np.arange(n)
    positions = np.sin(k[:, None] * 0.01 + np.arange(8)[None, :])
    times = T0 + k * 10_000_000
    messages = []
    for i in range(n):
        header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(int(times[i]), 10**9)), "")
        msg = T["sensor_msgs/msg/JointState"](header, names, positions[i], np.zeros(0), np.zeros(0))
        messages.append(bytes(ts.serialize_cdr(msg, "sensor_msgs/msg/JointState")))
    out = {}
    for storage, plugin in (("mcap", StoragePlugin.MCAP), ("db3", StoragePlugin.SQLITE3)):
        path = folder / f"arm_{storage}"
        with Writer(path, version=9, storage_plugin=plugin) as writer:
            conn = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=ts)
            for t, data in zip(times.tolist(), messages, strict=True):
                writer.write(conn, t, data)
        out[storage] = path
    return out


def write_big_bag(folder: Path, minutes: float) -> Path:
    """1 kHz, 30 joints, MCAP: one message serialized by rosbags, the others patched from it."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    names = [f"joint_{i}" for i in range(30)]
    header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](0, 0), "")
    template = bytes(
        ts.serialize_cdr(
            T["sensor_msgs/msg/JointState"](header, names, np.zeros(30), np.zeros(0), np.zeros(0)),
            "sensor_msgs/msg/JointState",
        )
    )
    offset = len(template) - 8 - 8 * 30  # the positions end 8 bytes (two empty sequences) before the end
    n, block = int(minutes * 60 * 1000), 100_000
    path = folder / "big_mcap"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=ts)
        for start in range(0, n, block):
            k = np.arange(start, min(n, start + block))
            t = T0 + k * 1_000_000
            buf = np.repeat(np.frombuffer(template, dtype=np.uint8)[None, :], len(k), axis=0)
            stamp = np.stack(np.divmod(t, 10**9), axis=1).astype("<i4")
            buf[:, 4:12] = stamp.view(np.uint8)
            pos = np.sin(k[:, None] * 0.001 + np.arange(30)[None, :]).astype("<f8")
            buf[:, offset : offset + 240] = pos.view(np.uint8)
            for time_ns, row in zip(t.tolist(), buf, strict=True):
                writer.write(conn, time_ns, row.tobytes())
    return path


def chain_urdf(path: Path, joints: int) -> Path:
    """A chain of boxes whose revolute joints are ``joint_0 …``, like the bags' JointStates."""
    links = "".join(
        f'<link name="l{i}"><visual><geometry><box size="0.05 0.05 0.2"/></geometry></visual></link>'
        for i in range(joints + 1)
    )
    chain = "".join(
        f'<joint name="joint_{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="0 0 0.2"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        for i in range(joints)
    )
    path.write_text(f'<robot name="chain">{links}{chain}</robot>')
    return path


FLOOR = "import rerun, numpy, rosbags.rosbag2"
"""What ``r2d2-viz --bag`` imports before it reads anything."""


def whole_commands(folder: Path, bags: dict[str, Path], rerun: str | None, repeats: int) -> dict[str, float]:
    """Median wall seconds of the import floor, ``r2d2-viz --bag … --save`` per storage and ``rerun mcap
    convert``, each run ``repeats`` times, alternating."""
    app = str(Path(PY).parent / "r2d2-viz")
    urdf = chain_urdf(folder / "arm8.urdf", 8)
    commands = {"floor": [PY, "-c", FLOOR]}
    for storage, path in bags.items():
        commands[f"ours {storage}"] = [app, "--bag", str(path), "--urdf", str(urdf), "--save", str(folder / "o.rrd")]
    if rerun:
        commands["rerun mcap convert"] = [
            rerun,
            "mcap",
            "convert",
            str(storage_file(bags["mcap"])),
            "-o",
            str(folder / "r.rrd"),
        ]
    walls: dict[str, list[float]] = {name: [] for name in commands}
    for _ in range(repeats):
        for name, command in commands.items():
            walls[name].append(_command(command)[0])
    return {name: sorted(w)[len(w) // 2] for name, w in walls.items()}


def storage_file(bag_dir: Path) -> Path:
    return next(p for p in bag_dir.iterdir() if p.suffix in (".mcap", ".db3"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--minutes", type=float, default=60.0, help="length of the 100 Hz, 8-joint bag")
    parser.add_argument("--big-minutes", type=float, default=60.0, help="length of the 1 kHz, 30-joint bag")
    parser.add_argument("--smoke", action="store_true", help="2 min and 1 min: a quick check that it all runs")
    args = parser.parse_args()
    if args.smoke:
        args.minutes, args.big_minutes = 2.0, 1.0
    rerun = _rerun()
    with tempfile.TemporaryDirectory(prefix="r2d2-bags-") as tmp:
        folder = Path(tmp)
        t = time.perf_counter()
        bags = write_arm_bags(folder, args.minutes)
        n = int(args.minutes * 6000)
        print(
            f"wrote {n:,} JointState messages (8 joints, 100 Hz, {args.minutes:g} min) with rosbags, both storages, "
            f"in {time.perf_counter() - t:.1f} s"
        )
        print(f"\n{'reader':<46} {'storage':<8} {'decode s':>9} {'µs/msg':>7} {'wall s':>7} {'peak MB':>8}")
        rows: dict[tuple[str, str], float] = {}
        for storage, path in bags.items():
            entries = [("ours: BagPass to arrays", _child(OURS, str(path), "8"))]
            entries.append(("rosbags: deserialize_cdr per message", _child(ROSBAGS, str(path))))
            if storage == "mcap":
                entries.append(
                    ("rerun.chunk.McapReader (ros2msg) to arrays", _child(RERUN_READER, str(storage_file(path))))
                )
            for name, (wall, rss, out) in entries:
                decode, count, _, _ = out.split()
                assert int(count) == n, (name, count)
                rows[(name, storage)] = float(decode)
                per = f"{float(decode) / n * 1e6:.2f}"
                print(f"{name:<46} {storage:<8} {float(decode):>9.2f} {per:>7} {wall:>7.2f} {rss:>8.0f}")
            if storage == "mcap" and rerun:
                wall, rss = _command([rerun, "mcap", "convert", str(storage_file(path)), "-o", str(folder / "arm.rrd")])
                rows[("rerun mcap convert", storage)] = wall
                name = "rerun mcap convert (.mcap to .rrd, plots only)"
                print(f"{name:<46} {storage:<8} {'':>9} {'':>7} {wall:>7.2f} {rss:>8.0f}")
        ours_mcap, ours_db3 = rows[("ours: BagPass to arrays", "mcap")], rows[("ours: BagPass to arrays", "db3")]
        slow = "rosbags: deserialize_cdr per message"
        print(
            f"\nours vs rosbags per message: {rows[(slow, 'mcap')] / ours_mcap:.1f}x faster (mcap), "
            f"{rows[(slow, 'db3')] / ours_db3:.1f}x (db3)"
        )
        if ("rerun mcap convert", "mcap") in rows:
            convert = rows[("rerun mcap convert", "mcap")]
            print(
                f"ours (decode only) / rerun mcap convert (whole command): {ours_mcap / convert:.2f} (mcap), "
                f"{ours_db3 / convert:.2f} (db3)"
            )
        walls = whole_commands(folder, bags, rerun, 1 if args.smoke else 3)
        floor = walls["floor"]
        print(f"\nwhole commands, medians: import floor {floor:.2f} s", end="")
        for storage in bags:
            print(f"; r2d2-viz --bag ({storage}) --save .rrd {walls[f'ours {storage}']:.2f} s", end="")
        if "rerun mcap convert" in walls:
            convert = walls["rerun mcap convert"]
            print(f"; rerun mcap convert {convert:.2f} s")
            for storage, goal in (("mcap", 1.5), ("db3", 3.0)):
                ratio = (walls[f"ours {storage}"] - floor) / convert
                verdict = "met" if ratio <= goal else "NOT met"
                what = f"  ({storage}) work beyond the floor / rerun mcap convert"
                print(f"{what}: {ratio:.2f}x (goal <= {goal:g}x) {verdict}")
        print()
        for path in bags.values():
            shutil.rmtree(path)

        t = time.perf_counter()
        big = write_big_bag(folder, args.big_minutes)
        size = storage_file(big).stat().st_size / 1e6
        print(
            f"\nwrote {int(args.big_minutes * 60_000):,} JointState messages (30 joints, 1 kHz, "
            f"{args.big_minutes:g} min, {size:,.0f} MB .mcap) in {time.perf_counter() - t:.1f} s"
        )
        _, floor, _ = _child(MEMORY, str(big), "0")
        wall, rss, out = _child(MEMORY, str(big), "1")
        decode = float(out.split()[0])
        print(
            f"BagPass, windows of 10,000: peak RSS {rss:.0f} MB (imports alone {floor:.0f} MB; goal < 400 MB), "
            f"decode {decode:.1f} s, wall {wall:.1f} s"
        )
        urdf30 = chain_urdf(folder / "arm30.urdf", 30)
        app = str(Path(PY).parent / "r2d2-viz")
        minutes = args.big_minutes  # the .rrd of an hour at 1 kHz with 30 joints is ~5 GB; removed after
        wall, rss = _command([app, "--bag", str(big), "--urdf", str(urdf30), "--save", str(folder / "big.rrd")])
        print(
            f"r2d2-viz --bag (1 kHz, 30 joints, {minutes:g} min) --save .rrd: peak RSS {rss:.0f} MB "
            f"(goal < 400 MB), wall {wall:.1f} s, .rrd {(folder / 'big.rrd').stat().st_size / 1e9:.1f} GB"
        )
        (folder / "big.rrd").unlink()


if __name__ == "__main__":
    main()
