#!/usr/bin/env python3
"""Display topics from bags (issue 18): a point-cloud bag replayed, beside ``rerun mcap convert``.

    python benchmarks/clouds.py            # 2 min of 10 Hz, 50,000-point PointCloud2 (xyz + rgb), ~1 GB .mcap
    python benchmarks/clouds.py --smoke    # 10 s of 10 Hz, 5,000 points: a CI smoke run, no thresholds

The bag is written inside the benchmark by ``rosbags`` (its writer; one cloud serialized by its serializer, the
stamps and points patched per message), MCAP storage. Side by side on the same file, alternating, medians:

* ``r2d2-viz --bag BAG --save out.rrd``: our decoder (numpy views over the CDR bytes), colours from the packed rgb
  field, each cloud in its frame at its time;
* ``rerun mcap convert BAG -o out.rrd`` (the CLI of rerun-sdk): Rerun's own decoders in Rust, positions only
  (it draws no colour: Rerun 0.41 writes rgb as a separate column);
* the import floor (``import rerun, numpy``).

Goal: ours ≤ 1.5× ``rerun mcap convert``. Then a live replay at ``--speed 1`` (``--save --realtime``, paced on the
wall clock): each cloud's lateness (when it was handed to Rerun minus when it was due, from the app's pacing log)
p50 / p99 / max (goal p99 ≤ 100 ms) and the peak RSS (goal < 1 GB).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

PY = sys.executable
T0 = 1_700_000_000_000_000_000
LAUNCH = "import os, subprocess, sys; p = subprocess.Popen(sys.argv[1:]); print(os.wait4(p.pid, 0)[2].ru_maxrss / 1024)"


def _command(command: list[str], env: dict[str, str] | None = None) -> tuple[float, float]:
    """Wall seconds and peak RSS (MB) of a command, started from a small launcher."""
    start = time.perf_counter()
    out = subprocess.run(
        [PY, "-c", LAUNCH, *command], capture_output=True, text=True, check=True, env={**os.environ, **(env or {})}
    )
    return time.perf_counter() - start, float(out.stdout.split()[-1])


def write_cloud_bag(folder: Path, seconds: float, points: int, rate: float = 10.0) -> Path:
    """A rosbag2 (MCAP) of ``/points``: ``points`` xyz + packed rgb per cloud, ``rate`` Hz for ``seconds``."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    field, cloud_t = ts.types["sensor_msgs/msg/PointField"], ts.types["sensor_msgs/msg/PointCloud2"]
    header_t, time_t = ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    fields = [field("x", 0, 7, 1), field("y", 4, 7, 1), field("z", 8, 7, 1), field("rgb", 12, 7, 1)]
    rng = np.random.default_rng(0)
    data = np.zeros(points, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "<u4")])
    msg = cloud_t(header_t(time_t(0, 0), "lidar"), 1, points, fields, False, 16, 16 * points, data.view(np.uint8), True)
    template = bytearray(ts.serialize_cdr(msg, "sensor_msgs/msg/PointCloud2"))
    offset = len(template) - 1 - 16 * points  # data[] then is_dense (one byte) end the message
    assert int.from_bytes(template[offset - 4 : offset], "little") == 16 * points  # data[]'s length precedes it
    path = folder / "clouds"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/points", "sensor_msgs/msg/PointCloud2", typestore=ts)
        for k in range(round(seconds * rate)):
            t = T0 + round(k * 1e9 / rate)
            data["x"], data["y"] = rng.uniform(-20, 20, points), rng.uniform(-20, 20, points)
            data["z"] = rng.uniform(0, 3, points)
            data["rgb"] = rng.integers(0, 1 << 24, points, dtype=np.uint32)
            body = bytearray(template)
            body[4:8] = int(t // 1_000_000_000).to_bytes(4, "little", signed=True)  # header.stamp, after the
            body[8:12] = int(t % 1_000_000_000).to_bytes(4, "little")  # 4-byte encapsulation header
            body[offset : offset + 16 * points] = data.view(np.uint8).tobytes()
            writer.write(connection, t, bytes(body))
    return path


def _percentiles(log: Path) -> tuple[float, float, float, int]:
    lateness = [float(line.split()[1]) for line in log.read_text().splitlines() if line.startswith("f ")]
    values = np.array(lateness) * 1000
    return float(np.percentile(values, 50)), float(np.percentile(values, 99)), float(values.max()), len(values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=120.0, help="length of the 10 Hz cloud bag")
    parser.add_argument("--points", type=int, default=50_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--smoke", action="store_true", help="10 s of 5,000-point clouds, one run each")
    args = parser.parse_args()
    if args.smoke:
        args.seconds, args.points, args.repeats = 10.0, 5_000, 1
    app = str(Path(PY).parent / "r2d2-viz")
    rerun = str(Path(PY).parent / "rerun") if (Path(PY).parent / "rerun").exists() else shutil.which("rerun")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        t = time.perf_counter()
        bag = write_cloud_bag(folder, args.seconds, args.points)
        size = sum(f.stat().st_size for f in bag.iterdir()) / 1e6
        print(
            f"bag: {args.seconds:g} s of 10 Hz {args.points:,}-point clouds, {size:.0f} MB (written in "
            f"{time.perf_counter() - t:.1f} s)"
        )
        commands = {
            "floor (import rerun, numpy)": [PY, "-c", "import rerun, numpy"],
            "r2d2-viz --bag --save": [app, "--bag", str(bag), "--save", str(folder / "ours.rrd")],
        }
        if rerun:
            mcap = next(bag.glob("*.mcap"))
            commands["rerun mcap convert"] = [rerun, "mcap", "convert", str(mcap), "-o", str(folder / "rerun.rrd")]
        walls: dict[str, list[float]] = {name: [] for name in commands}
        peaks: dict[str, list[float]] = {name: [] for name in commands}
        for _ in range(args.repeats):
            for name, command in commands.items():
                wall, peak = _command(command)
                walls[name].append(wall)
                peaks[name].append(peak)
        median = {name: sorted(w)[len(w) // 2] for name, w in walls.items()}
        for name in commands:
            print(
                f"{name}: wall {median[name]:.2f} s (runs: {', '.join(f'{w:.2f}' for w in walls[name])}), "
                f"peak RSS {max(peaks[name]):.0f} MB"
            )
        if rerun:
            ratio = median["r2d2-viz --bag --save"] / median["rerun mcap convert"]
            print(f"ours / rerun mcap convert: {ratio:.2f}x (goal <= 1.5x)")
        log = folder / "pacing.log"
        live_seconds = min(args.seconds, 30.0) if args.smoke else args.seconds
        live = [app, "--bag", str(bag), "--save", str(folder / "live.rrd"), "--realtime", "--speed", "1"]
        wall, peak = _command(live, env={"R2D2_VIZ_PACING_LOG": str(log)})
        p50, p99, worst, n = _percentiles(log)
        print(
            f"live replay at --speed 1 ({live_seconds:g} s of bag, wall {wall:.1f} s): {n} hand-overs, lateness "
            f"p50 {p50:.1f} / p99 {p99:.1f} / max {worst:.1f} ms (goal p99 <= 100 ms); peak RSS {peak:.0f} MB "
            "(goal < 1 GB)"
        )


if __name__ == "__main__":
    main()
