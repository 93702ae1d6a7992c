#!/usr/bin/env python3
"""Big bags (issue 23): a gigabyte sensor bag replayed, beside ``rerun mcap convert``, in one run.

    python benchmarks/bigbag.py                      # 150 s sensor bag (~3 GB) and a 30 s one; ~10 min
    python benchmarks/bigbag.py --data /work/bigdata # keep the bags there (reused when present)
    python benchmarks/bigbag.py --smoke              # 3 s and 1 s of bag, every row once: CI, no thresholds
    python benchmarks/bigbag.py --zstd               # the same bags with zstd-compressed chunks (2.85 GB)
    python benchmarks/bigbag.py --only arm           # only the 1 h × 100 Hz JointState bag's row (~1 min)
    python benchmarks/bigbag.py --only layouts --seconds 20   # every layout (issue 48) of a 20 s bag, side by side

The bag is written inside the benchmark by ``rosbags`` (its writer, MCAP storage, uncompressed 1 MB chunks as
rosbags writes them; ``--db3`` also writes it as .db3), like the issue's: a camera (``Image`` rgb8 640×480 at
15 Hz, its JPEG ``CompressedImage`` and its ``CameraInfo``), a 32,768-point ``PointCloud2`` (x, y, z, intensity
float32) at 10 Hz, a 720-beam ``LaserScan`` at 20 Hz, ``/tf`` (odom → base_link, 50 Hz), ``/tf_static`` (the
sensors' mounts, map → odom), ``/odom`` and ``/joint_states`` (the tutorial R2D2's tilt, swivel, periscope) at
50 Hz, an ``OccupancyGrid`` ``/map`` (at the start and every 30 s) and ``/robot_description`` (the tutorial R2D2
on a base_link with the sensors' links). Camera frames and clouds are made once (a moving gradient with noise,
JPEG-encoded by Pillow; lidar rings) and reused, their stamps patched per message.

Every figure is a whole command in a subprocess, side by side in the same run, alternating, medians of
``--rounds``:

* wall and CPU time of ``r2d2-viz --bag BAG.mcap --save out.rrd`` and ``rerun mcap convert BAG.mcap -o out.rrd``
  (the ``rerun`` binary beside this Python; issue 38's goal: ≤ 0.5× its wall at ≤ 300 MB);
* **peak anonymous memory**: ``RssAnon`` + ``RssShmem`` of the process and all its descendants (found through
  ``/proc/PID/task/*/children``), summed, polled every 20 ms from ``/proc/PID/status``. File pages (a bag read
  through ``mmap``, shared libraries) are not counted: they are the page cache's, not the program's; shared memory
  (a worker's ring) is;
* **every layout** (issue 48, ``--layouts``, ``benchmarks/bag_layouts.py``): the same content written by rosbags'
  writer, as ``ros2 bag record`` writes MCAP (rosbag2_storage_mcap's defaults: 768 KiB chunks, uncompressed and
  zstd), topic by topic, and as ``.db3``; each one's chunk layout printed, ``--save`` beside ``rerun mcap convert``
  (which reads MCAP only), the layouts and the commands alternating round by round;
* before every whole command of a side-by-side figure, the outputs are deleted and the disk synced (an older output
  left in place makes the next writer's page-cache writes dearer and a ratio flattering);
* the same for a 30 s bag of the same kind (the goal: the 150 s bag ≤ 500 MB and ≤ 1.25× (+50 MB) of it);
* a live replay's **time to first data**: ``r2d2-viz --bag BAG --save x.rrd --realtime`` with
  ``R2D2_VIZ_PACING_LOG=path`` (the pacing hook of ``r2d2_viz/pacing.py``), from process start to the log's first
  line (the hook flushes it as soon as the first sample has gone out), and to when the log appears (paced sending
  begins); the run is stopped with SIGINT after ``--live-seconds``, and its peak RssAnon over that window is
  reported;
* ``--start-offset`` (10 s before the end) beside a head run (``--duration 2``; issue 38's goal ≤ 1.5× its wall),
  and ``--start-offset … --duration 2`` (the seek alone, the same length of bag as the head run);
  ``--topics /scan /tf /tf_static`` as a fraction of the full conversion's wall (≤ 25 %); their peak RssAnon
  (≤ 300 MB);
* the 1 h × 100 Hz JointState bag of ``benchmarks/bags.py`` (its writer, reused): the work beyond the import
  floor (``python -c "import rerun, numpy"``) over ``rerun mcap convert``'s wall (goal ≤ 2×).

Goals are printed beside the figures; the script never fails on a threshold. The machine may be shared (2
cores here): run it on a quiet machine for figures to quote.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

PY = sys.executable
APP = str(Path(PY).parent / "r2d2-viz")
T0 = 1_700_000_000_000_000_000
ASSETS = Path(__file__).resolve().parent.parent / "assets"
POLL_S = 0.02
CAMERA_W, CAMERA_H = 640, 480
CLOUD_RINGS, CLOUD_COLUMNS = 32, 1024  # 32,768 points
SCAN_BEAMS = 720
FRAMES = 8
"""Camera frames (and clouds) made once and cycled through."""
TOPIC_RATES = {
    "/camera/image_raw": 15.0,
    "/camera/image_raw/compressed": 15.0,
    "/camera/camera_info": 15.0,
    "/points": 10.0,
    "/scan": 20.0,
    "/tf": 50.0,
    "/odom": 50.0,
    "/joint_states": 50.0,
    "/map": 1 / 30,
}


def _rerun() -> str | None:
    exe = Path(PY).parent / "rerun"
    return str(exe) if exe.exists() else shutil.which("rerun")


# --- the bag ------------------------------------------------------------------------------------------


def sensor_urdf() -> str:
    """The tutorial R2D2 (``assets/r2d2.urdf``: tilt, swivel, periscope) on a base_link, with the sensors' links."""
    r2d2 = (ASSETS / "r2d2.urdf").read_text()
    extra = '<link name="base_link"/>' + _fixed("base_link", "axis", "0 0 0.75", "0 0 0")
    for link, parent, xyz, rpy in MOUNTS:
        extra += f'<link name="{link}"/>' + _fixed(parent, link, xyz, rpy)
    return r2d2.replace("</robot>", extra + "</robot>")


def _fixed(parent: str, child: str, xyz: str, rpy: str) -> str:
    return (
        f'<joint name="{child}_mount" type="fixed"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/></joint>'
    )


MOUNTS = [
    ("camera_link", "base_link", "0.25 0 1.1", "0 0 0"),
    ("camera_optical", "camera_link", "0 0 0", "-1.5707963 0 -1.5707963"),
    ("laser", "base_link", "0.3 0 0.2", "0 0 0"),
    ("lidar", "base_link", "0 0 1.5", "0 0 0"),
]
"""child, parent, xyz, rpy: the URDF's fixed sensor joints, also published on /tf_static (as
robot_state_publisher does)."""


def _quat_rpy(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    cr, sr, cp, sp, cy, sy = (f(a / 2) for a in (roll, pitch, yaw) for f in (np.cos, np.sin))
    return (
        float(sr * cp * cy - cr * sp * sy),
        float(cr * sp * cy + sr * cp * sy),
        float(cr * cp * sy - sr * sp * cy),
        float(cr * cp * cy + sr * sp * sy),
    )


def camera_frames(n: int = FRAMES) -> list[np.ndarray]:
    """``n`` rgb8 frames: a gradient moving across, a bright disc, sensor noise."""
    rng = np.random.default_rng(1)
    y, x = np.mgrid[0:CAMERA_H, 0:CAMERA_W]
    frames = []
    for k in range(n):
        shift = k * CAMERA_W / n
        r = (x + shift) % CAMERA_W * 255 / CAMERA_W
        g = y * 255 / CAMERA_H
        b = 128 + 100 * np.sin((x + y + 4 * shift) / 40)
        disc = (x - 200 - shift / 2) ** 2 + (y - 240) ** 2 < 60**2
        img = np.stack([r, g, b], axis=-1)
        img[disc] = (250, 240, 200)
        img += rng.normal(0, 6, img.shape)
        frames.append(np.clip(img, 0, 255).astype(np.uint8))
    return frames


def _jpeg(frame: np.ndarray) -> bytes:
    import io

    from PIL import Image

    out = io.BytesIO()
    Image.fromarray(frame).save(out, format="JPEG", quality=90)
    return out.getvalue()


def lidar_clouds(n: int = FRAMES) -> list[np.ndarray]:
    """``n`` clouds of 32 rings × 1024 columns: a room's walls, with range noise; x, y, z, intensity float32."""
    rng = np.random.default_rng(2)
    azimuth = np.linspace(-np.pi, np.pi, CLOUD_COLUMNS, endpoint=False)[None, :]
    elevation = np.radians(np.linspace(-15, 15, CLOUD_RINGS))[:, None]
    clouds = []
    for k in range(n):
        walls = np.minimum(
            8 / np.maximum(np.abs(np.cos(azimuth + k * 0.02)), 1e-3),
            12 / np.maximum(np.abs(np.sin(azimuth + k * 0.02)), 1e-3),
        )
        ranges = np.minimum(walls, 1.5 / np.maximum(np.abs(np.sin(elevation)), 1e-3)) + rng.normal(
            0, 0.02, (CLOUD_RINGS, CLOUD_COLUMNS)
        )
        cloud = np.zeros((CLOUD_RINGS, CLOUD_COLUMNS), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("i", "<f4")])
        cloud["x"] = ranges * np.cos(elevation) * np.cos(azimuth)
        cloud["y"] = ranges * np.cos(elevation) * np.sin(azimuth)
        cloud["z"] = ranges * np.sin(elevation)
        cloud["i"] = rng.uniform(0, 255, ranges.shape)
        clouds.append(cloud.reshape(-1))
    return clouds


class _Messages:
    """Serialized messages of every topic: big ones from templates (stamp patched), small ones by rosbags."""

    def __init__(self, seconds: float) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.ts = get_typestore(Stores.ROS2_HUMBLE)
        self.T = self.ts.types
        frames = camera_frames()
        self.images = [self._image(f) for f in frames]
        self.jpegs = [
            self._ser(
                self.T["sensor_msgs/msg/CompressedImage"](self._header(0, "camera_optical"), "jpeg", data),
                "sensor_msgs/msg/CompressedImage",
            )
            for data in (np.frombuffer(_jpeg(f), dtype=np.uint8) for f in frames)
        ]
        self.clouds = [self._cloud(c) for c in lidar_clouds()]
        self.seconds = seconds

    def _ser(self, msg: object, msgtype: str) -> bytearray:
        return bytearray(bytes(self.ts.serialize_cdr(msg, msgtype)))

    def _header(self, t: int, frame: str) -> object:
        return self.T["std_msgs/msg/Header"](self.T["builtin_interfaces/msg/Time"](*divmod(t, 10**9)), frame)

    def _image(self, frame: np.ndarray) -> bytearray:
        msg = self.T["sensor_msgs/msg/Image"](
            self._header(0, "camera_optical"), CAMERA_H, CAMERA_W, "rgb8", 0, 3 * CAMERA_W, frame.reshape(-1)
        )
        return self._ser(msg, "sensor_msgs/msg/Image")

    def _cloud(self, cloud: np.ndarray) -> bytearray:
        field_t = self.T["sensor_msgs/msg/PointField"]
        fields = [field_t(name, 4 * i, 7, 1) for i, name in enumerate(("x", "y", "z", "intensity"))]
        msg = self.T["sensor_msgs/msg/PointCloud2"](
            self._header(0, "lidar"), CLOUD_RINGS, CLOUD_COLUMNS, fields, False, 16, 16 * CLOUD_COLUMNS,
            cloud.view(np.uint8), True,
        )  # fmt: skip
        return self._ser(msg, "sensor_msgs/msg/PointCloud2")

    @staticmethod
    def _stamped(template: bytearray, t: int) -> bytearray:
        """The template with its header stamp (after the 4-byte CDR encapsulation header) set to ``t``."""
        sec, nsec = divmod(t, 10**9)
        template[4:8] = sec.to_bytes(4, "little", signed=True)
        template[8:12] = nsec.to_bytes(4, "little")
        return template

    def message(self, topic: str, k: int, t: int) -> bytearray:
        T, s = self.T, (t - T0) * 1e-9
        if topic == "/camera/image_raw":
            return self._stamped(self.images[k % FRAMES], t)
        if topic == "/camera/image_raw/compressed":
            return self._stamped(self.jpegs[k % FRAMES], t)
        if topic == "/points":
            return self._stamped(self.clouds[k % FRAMES], t)
        if topic == "/camera/camera_info":
            fx = 525.0
            msg = T["sensor_msgs/msg/CameraInfo"](
                self._header(t, "camera_optical"), CAMERA_H, CAMERA_W, "plumb_bob", np.zeros(5),
                np.array([fx, 0, 320, 0, fx, 240, 0, 0, 1.0]), np.eye(3).reshape(-1),
                np.array([fx, 0, 320, 0, 0, fx, 240, 0, 0, 0, 1.0, 0]), 0, 0,
                T["sensor_msgs/msg/RegionOfInterest"](0, 0, 0, 0, False),
            )  # fmt: skip
            return self._ser(msg, "sensor_msgs/msg/CameraInfo")
        if topic == "/scan":
            angles = np.linspace(-np.pi, np.pi, SCAN_BEAMS, endpoint=False)
            ranges = np.minimum(
                4 / np.maximum(np.abs(np.cos(angles + 0.1 * s)), 1e-3),
                6 / np.maximum(np.abs(np.sin(angles + 0.1 * s)), 1e-3),
            ).astype(np.float32)
            msg = T["sensor_msgs/msg/LaserScan"](
                self._header(t, "laser"), -np.pi, np.pi, 2 * np.pi / SCAN_BEAMS, 0.0, 0.05, 0.1, 30.0, ranges,
                np.full(SCAN_BEAMS, 100, dtype=np.float32),
            )  # fmt: skip
            return self._ser(msg, "sensor_msgs/msg/LaserScan")
        x, y, yaw = 2 * np.cos(0.05 * s), 2 * np.sin(0.05 * s), 0.05 * s + np.pi / 2
        if topic == "/tf":
            return self._ser(
                T["tf2_msgs/msg/TFMessage"]([self._transform(t, "odom", "base_link", (x, y, 0), yaw)]),
                "tf2_msgs/msg/TFMessage",
            )
        if topic == "/odom":
            pose = T["geometry_msgs/msg/Pose"](
                T["geometry_msgs/msg/Point"](x, y, 0.0), T["geometry_msgs/msg/Quaternion"](*_quat_rpy(0, 0, yaw))
            )
            zero = T["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.0)
            twist = T["geometry_msgs/msg/Twist"](T["geometry_msgs/msg/Vector3"](0.1, 0.0, 0.0), zero)
            msg = T["nav_msgs/msg/Odometry"](
                self._header(t, "odom"), "base_link", T["geometry_msgs/msg/PoseWithCovariance"](pose, np.zeros(36)),
                T["geometry_msgs/msg/TwistWithCovariance"](twist, np.zeros(36)),
            )  # fmt: skip
            return self._ser(msg, "nav_msgs/msg/Odometry")
        if topic == "/joint_states":
            positions = np.array([-0.25 + 0.25 * np.sin(s), 0.5 * s, -0.25 + 0.25 * np.cos(0.5 * s)])
            msg = T["sensor_msgs/msg/JointState"](
                self._header(t, ""), ["tilt", "swivel", "periscope"], positions, np.zeros(0), np.zeros(0)
            )
            return self._ser(msg, "sensor_msgs/msg/JointState")
        if topic == "/map":
            return self._map(t)
        if topic == "/tf_static":
            transforms = [self._transform(t, "map", "odom", (0, 0, 0), 0.0)]
            for child, parent, xyz, rpy in MOUNTS:
                q = _quat_rpy(*(float(v) for v in rpy.split()))
                transforms.append(self._transform(t, parent, child, tuple(float(v) for v in xyz.split()), q))
            return self._ser(T["tf2_msgs/msg/TFMessage"](transforms), "tf2_msgs/msg/TFMessage")
        if topic == "/robot_description":
            return self._ser(T["std_msgs/msg/String"](sensor_urdf()), "std_msgs/msg/String")
        raise KeyError(topic)

    def _transform(
        self, t: int, parent: str, child: str, xyz: tuple[float, ...], rot: float | tuple[float, ...]
    ) -> object:
        T = self.T
        q = _quat_rpy(0, 0, rot) if isinstance(rot, float) else rot
        return T["geometry_msgs/msg/TransformStamped"](
            self._header(t, parent), child,
            T["geometry_msgs/msg/Transform"](T["geometry_msgs/msg/Vector3"](*map(float, xyz)),
                                             T["geometry_msgs/msg/Quaternion"](*q)),
        )  # fmt: skip

    def _map(self, t: int) -> bytearray:
        T, n = self.T, 384
        grid = np.zeros((n, n), dtype=np.int8)
        grid[:8], grid[-8:], grid[:, :8], grid[:, -8:] = 100, 100, 100, 100
        grid[150:170, 100:300] = 100
        grid[250:, 300:] = -1
        info = T["nav_msgs/msg/MapMetaData"](
            T["builtin_interfaces/msg/Time"](*divmod(t, 10**9)), 0.05, n, n,
            T["geometry_msgs/msg/Pose"](T["geometry_msgs/msg/Point"](-9.6, -9.6, 0.0),
                                        T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0)),
        )  # fmt: skip
        return self._ser(
            T["nav_msgs/msg/OccupancyGrid"](self._header(t, "map"), info, grid.reshape(-1)),
            "nav_msgs/msg/OccupancyGrid",
        )


TYPES = {
    "/robot_description": "std_msgs/msg/String",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/camera/image_raw": "sensor_msgs/msg/Image",
    "/camera/image_raw/compressed": "sensor_msgs/msg/CompressedImage",
    "/camera/camera_info": "sensor_msgs/msg/CameraInfo",
    "/points": "sensor_msgs/msg/PointCloud2",
    "/scan": "sensor_msgs/msg/LaserScan",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/odom": "nav_msgs/msg/Odometry",
    "/joint_states": "sensor_msgs/msg/JointState",
    "/map": "nav_msgs/msg/OccupancyGrid",
}


def schedule(seconds: float) -> list[tuple[int, str, int]]:
    """``(log time, topic, index)`` of every message, in time order: latched topics first, then each topic at its
    rate (phases staggered a little, as separate publishers are)."""
    events: list[tuple[int, str, int]] = [(T0, "/robot_description", 0), (T0, "/tf_static", 0)]
    for order, (topic, rate) in enumerate(TOPIC_RATES.items()):
        n = int(np.floor(seconds * rate - 1e-9)) + 1
        phase = 0 if topic == "/map" else order * 1_000_003
        events += [(T0 + phase + round(k * 1e9 / rate), topic, k) for k in range(n)]
    return sorted(events, key=lambda e: e[0])


def write_sensor_bag(path: Path, seconds: float, storage: str = "mcap", zstd: bool = False) -> Path:
    """A rosbag2 directory at ``path`` (written in a scratch folder beside it, moved into place when complete);
    ``zstd``: its MCAP chunks compressed (rosbags' storage compression)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.rosbag2.enums import CompressionFormat, CompressionMode

    scratch = path.with_name(path.name + ".partial")
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)
    partial = scratch / path.name
    messages = _Messages(seconds)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    writer = Writer(partial, version=9, storage_plugin=plugin)
    if zstd:
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with writer:
        connections = {
            topic: writer.add_connection(topic, msgtype, typestore=messages.ts) for topic, msgtype in TYPES.items()
        }
        for t, topic, k in schedule(seconds):
            writer.write(connections[topic], t, messages.message(topic, k, t))
    partial.rename(path)
    scratch.rmdir()
    return path


def sensor_bag(data: Path, seconds: float, storage: str = "mcap", zstd: bool = False) -> Path:
    """The bag file (``.mcap`` or ``.db3``) of ``seconds`` in ``data``: reused if there, else written."""
    folder = data / f"sensors_{seconds:g}s_{storage}{'_zstd' if zstd else ''}"
    if not folder.exists():
        t = time.perf_counter()
        write_sensor_bag(folder, seconds, storage, zstd)
        print(f"wrote {folder} in {time.perf_counter() - t:.0f} s", file=sys.stderr)
    return next(p for p in folder.iterdir() if p.suffix == f".{storage}")


# --- measuring ----------------------------------------------------------------------------------------


def _tree(pid: int) -> list[int]:
    """``pid`` and its descendants (through every thread's ``children`` file)."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        try:
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    todo += [int(c) for c in f.read().split()]
        except OSError:
            continue  # gone meanwhile
    return out


def rss_anon_kb(pid: int) -> int:
    """RssAnon + RssShmem of ``pid`` and its descendants, summed (kB): shared memory (a worker's ring) counted."""
    total = 0
    for p in _tree(pid):
        try:
            with open(f"/proc/{p}/status") as f:
                for line in f:
                    if line.startswith(("RssAnon:", "RssShmem:")):
                        total += int(line.split()[1])
        except OSError:
            continue
    return total


def fresh(*outputs: Path) -> None:
    """``outputs`` deleted and the disk synced before a command: an older output left in place makes the next
    writer's page-cache writes dearer (issue 48: 0.74× measured that way, 1.11× with outputs deleted)."""
    for out in outputs:
        out.unlink(missing_ok=True)
    os.sync()


@dataclass
class Run:
    wall: float
    peak_anon_mb: float
    returncode: int
    stderr: str
    marks: dict[str, float] = field(default_factory=dict)
    """Seconds from start to when a watched file appeared (``created``) and got its first bytes (``first``)."""
    stdout: str = ""
    cpu: float = float("nan")
    """User + system seconds of the process and the children it waited for (``os.wait4``)."""


def run_watched(
    command: list[str], *, env: dict[str, str] | None = None, watch: Path | None = None, stop_after: float | None = None
) -> Run:
    """Run ``command`` to its end (or SIGINT it after ``stop_after`` s), polling its tree's RssAnon every 20 ms."""
    start = time.perf_counter()
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env={**os.environ, **(env or {})})
    out: list[bytes] = []
    err: list[bytes] = []
    readers = [
        threading.Thread(target=lambda: out.append(proc.stdout.read() if proc.stdout else b""), daemon=True),
        threading.Thread(target=lambda: err.append(proc.stderr.read() if proc.stderr else b""), daemon=True),
    ]
    for reader in readers:
        reader.start()
    peak, marks, cpu = 0, {}, float("nan")
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:  # reaped here, for its CPU time: Popen is told the exit status
            proc.returncode, cpu = os.waitstatus_to_exitcode(status), usage.ru_utime + usage.ru_stime
            break
        peak = max(peak, rss_anon_kb(proc.pid))
        now = time.perf_counter() - start
        if watch is not None and "first" not in marks and watch.exists():
            marks.setdefault("created", now)
            if watch.stat().st_size > 0:
                marks["first"] = now
        if stop_after is not None and now > stop_after:
            proc.send_signal(signal.SIGINT)
            stop_after = None
        time.sleep(POLL_S)
    wall = time.perf_counter() - start
    for reader in readers:
        reader.join()
    return Run(
        wall, peak / 1024, proc.returncode, b"".join(err).decode(errors="replace"), marks,
        b"".join(out).decode(errors="replace"), cpu,
    )  # fmt: skip


def _checked(run: Run, command: list[str]) -> Run:
    if run.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed ({run.returncode}):\n{run.stderr[-2000:]}")
    return run


def _med(xs: list[float]) -> float:
    return float(statistics.median(xs))


def _seconds(value: float, limit: float) -> str:
    return f"{value:.1f} s" if value == value else f"not within {limit:g} s"


# --- the report ---------------------------------------------------------------------------------------


@dataclass
class Table:
    rows: list[tuple[str, str, str, str, str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    figures: dict[str, float] = field(default_factory=dict)

    def add(self, figure: str, ours: str, rerun: str = "", ratio: str = "", goal: str = "") -> None:
        self.rows.append((figure, ours, rerun, ratio, goal))

    def print(self) -> None:
        print("\n| figure | r2d2-viz | `rerun mcap convert` | ratio | goal |\n|---|---:|---:|---:|---|")
        for row in self.rows:
            print("| " + " | ".join(row) + " |")
        for note in self.notes:
            print(f"\n{note}")


def _verdict(ok: bool, smoke: bool) -> str:
    return "" if smoke else (" met" if ok else " NOT met")


def side_by_side(bag: Path, rerun: str | None, rounds: int, out: Path) -> dict[str, list[Run]]:
    """``r2d2-viz --bag BAG --save`` and ``rerun mcap convert``, alternating, ``rounds`` times each."""
    commands = {"ours": [APP, "--bag", str(bag), "--save", str(out / "ours.rrd")]}
    if rerun is not None:
        commands["rerun"] = [rerun, "mcap", "convert", str(bag), "-o", str(out / "rerun.rrd")]
    runs: dict[str, list[Run]] = {name: [] for name in commands}
    for _ in range(rounds):
        for name, command in commands.items():
            fresh(out / "ours.rrd", out / "rerun.rrd")
            runs[name].append(_checked(run_watched(command), command))
    fresh(out / "ours.rrd", out / "rerun.rrd")
    return runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=150.0, help="length of the big bag (150 s: ~3 GB)")
    parser.add_argument("--small-seconds", type=float, default=30.0, help="length of the bag memory is compared to")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of each side-by-side figure (medians)")
    parser.add_argument("--live-seconds", type=float, default=20.0, help="how long the live replay runs")
    parser.add_argument("--data", type=Path, help="where the bags are kept and reused (default: a temporary dir)")
    parser.add_argument("--db3", action="store_true", help="also write the big bag as .db3 and replay it")
    parser.add_argument("--zstd", action="store_true", help="the sensor bags' chunks zstd-compressed (2.85 GB)")
    parser.add_argument("--arm-minutes", type=float, default=60.0, help="the 100 Hz JointState bag's length")
    parser.add_argument(
        "--only", choices=["arm", "layouts"], help="only these rows: the 100 Hz JointState bag's, or the layouts'"
    )
    parser.add_argument(
        "--layouts",
        type=lambda text: [x for x in text.split(",") if x],
        default=["rosbags", "rosbag2", "rosbag2_zstd", "topics", "db3"],
        help="the layouts measured side by side (comma-separated; see benchmarks/bag_layouts.py; '' for none)",
    )
    parser.add_argument("--json", type=Path, help="also write the figures here")
    parser.add_argument("--smoke", action="store_true", help="3 s and 1 s bags, every row once, no thresholds")
    args = parser.parse_args()
    if args.smoke:
        args.seconds, args.small_seconds, args.rounds, args.live_seconds, args.arm_minutes = 3.0, 1.0, 1, 8.0, 0.5
    rerun = _rerun()
    if args.only == "arm":
        if rerun is None:
            raise SystemExit("--only arm compares with `rerun mcap convert`: no rerun binary found")
        with tempfile.TemporaryDirectory(prefix="r2d2-bigbag-") as tmp:
            data = args.data or Path(tmp)
            data.mkdir(parents=True, exist_ok=True)
            table = Table()
            arm_rows(table, data, Path(tmp), rerun, args.arm_minutes, args.rounds, args.smoke)
            table.print()
            if args.json:
                args.json.write_text(json.dumps(table.figures, indent=2))
        return
    if args.only == "layouts":
        with tempfile.TemporaryDirectory(prefix="r2d2-bigbag-") as tmp:
            data = args.data or Path(tmp)
            data.mkdir(parents=True, exist_ok=True)
            table = Table()
            layout_rows(table, data, Path(tmp), rerun, args)
            table.print()
            if args.json:
                args.json.write_text(json.dumps(table.figures, indent=2))
        return
    with tempfile.TemporaryDirectory(prefix="r2d2-bigbag-") as tmp:
        scratch = Path(tmp)
        data = args.data or scratch
        data.mkdir(parents=True, exist_ok=True)
        big = sensor_bag(data, args.seconds, zstd=args.zstd)
        small = sensor_bag(data, args.small_seconds, zstd=args.zstd)
        size_gb = big.stat().st_size / 1e9
        table = Table()
        smoke = args.smoke
        table.notes.append(
            f"Bags: {args.seconds:g} s ({size_gb:.2f} GB) and {args.small_seconds:g} s "
            f"({small.stat().st_size / 1e9:.2f} GB), MCAP{' (zstd chunks)' if args.zstd else ''}, written by rosbags; "
            f"medians of {args.rounds} rounds, "
            "alternating; memory = peak RssAnon of the process tree, polled every 20 ms."
        )

        runs = side_by_side(big, rerun, args.rounds, scratch)
        ours_wall = _med([r.wall for r in runs["ours"]])
        ours_mem = _med([r.peak_anon_mb for r in runs["ours"]])
        table.figures |= {"big_ours_wall_s": ours_wall, "big_ours_anon_mb": ours_mem}
        if "rerun" in runs:
            rr_wall = _med([r.wall for r in runs["rerun"]])
            rr_mem = _med([r.peak_anon_mb for r in runs["rerun"]])
            table.figures |= {"big_rerun_wall_s": rr_wall, "big_rerun_anon_mb": rr_mem}
            ratio = ours_wall / rr_wall
            table.add(
                f"{args.seconds:g} s bag ({size_gb:.1f} GB) `--save` wall",
                f"{ours_wall:.1f} s",
                f"{rr_wall:.1f} s",
                f"{ratio:.2f}×",
                "≤ 0.5× (issue 38)" + _verdict(ratio <= 0.5, smoke),
            )
            ours_cpu, rr_cpu = _med([r.cpu for r in runs["ours"]]), _med([r.cpu for r in runs["rerun"]])
            table.figures |= {"big_ours_cpu_s": ours_cpu, "big_rerun_cpu_s": rr_cpu}
            table.add(
                "the same: CPU (user + system)", f"{ours_cpu:.1f} s", f"{rr_cpu:.1f} s", f"{ours_cpu / rr_cpu:.2f}×"
            )
            rerun_mem = f"{rr_mem:,.0f} MB"
        else:
            rerun_mem = "(no rerun binary)"
        table.add(
            f"{args.seconds:g} s bag: peak RssAnon",
            f"{ours_mem:,.0f} MB",
            rerun_mem,
            "",
            "≤ 300 MB (issue 38)" + _verdict(ours_mem <= 300, smoke),
        )
        small_runs = side_by_side(small, rerun, args.rounds, scratch)
        s_wall = _med([r.wall for r in small_runs["ours"]])
        s_mem = _med([r.peak_anon_mb for r in small_runs["ours"]])
        table.figures |= {"small_ours_wall_s": s_wall, "small_ours_anon_mb": s_mem}
        s_rr = (
            (_med([r.wall for r in small_runs["rerun"]]), _med([r.peak_anon_mb for r in small_runs["rerun"]]))
            if "rerun" in small_runs
            else None
        )
        table.add(
            f"{args.small_seconds:g} s bag `--save` wall",
            f"{s_wall:.1f} s",
            f"{s_rr[0]:.1f} s" if s_rr else "",
            f"{s_wall / s_rr[0]:.2f}×" if s_rr else "",
        )
        table.add(
            f"{args.small_seconds:g} s bag: peak RssAnon",
            f"{s_mem:,.0f} MB",
            f"{s_rr[1]:,.0f} MB" if s_rr else "",
            f"big / small {ours_mem / s_mem:.2f}×",
            f"big ≤ 1.25× small + 50 MB ({1.25 * s_mem + 50:,.0f} MB)" + _verdict(ours_mem <= 1.25 * s_mem + 50, smoke),
        )
        if args.db3:
            db3 = sensor_bag(data, args.seconds, "db3")
            command = [APP, "--bag", str(db3), "--save", str(scratch / "db3.rrd")]
            db3_runs = [_checked(run_watched(command), command) for _ in range(args.rounds)]
            db3_mem = _med([r.peak_anon_mb for r in db3_runs])
            table.add(
                f"{args.seconds:g} s bag as .db3 `--save`: wall, peak RssAnon",
                f"{_med([r.wall for r in db3_runs]):.1f} s, {db3_mem:,.0f} MB",
                "",
                "",
                "≤ 300 MB (issue 38)" + _verdict(db3_mem <= 300, smoke),
            )

        # Live replay: time to first data, memory while it plays.
        log = scratch / "pacing.log"
        live_cmd = [APP, "--bag", str(big), "--save", str(scratch / "live.rrd"), "--realtime"]
        firsts, creates, live_mem = [], [], []
        for _ in range(args.rounds):
            log.unlink(missing_ok=True)
            run = run_watched(live_cmd, env={"R2D2_VIZ_PACING_LOG": str(log)}, watch=log, stop_after=args.live_seconds)
            if run.returncode not in (0, 130, -signal.SIGINT):
                raise RuntimeError(f"live replay failed ({run.returncode}):\n{run.stderr[-2000:]}")
            creates.append(run.marks.get("created", float("nan")))
            firsts.append(run.marks.get("first", float("nan")))
            live_mem.append(run.peak_anon_mb)
        created, first = _med(creates), _med(firsts)  # nan: not within --live-seconds
        table.figures |= {"live_pacing_starts_s": created, "live_first_log_bytes_s": first}
        table.add(
            "live replay (`--save --realtime`): time to first data (the pacing log's first line)",
            _seconds(first, args.live_seconds),
            "",
            "",
            "≤ 2 s" + _verdict(first <= 2.0, smoke),
        )
        table.add("live replay: pacing starts (the pacing log is created)", _seconds(created, args.live_seconds))
        table.add(
            f"live replay: peak RssAnon over its first {args.live_seconds:g} s",
            f"{_med(live_mem):,.0f} MB",
            "",
            "",
            "≤ 500 MB" + _verdict(_med(live_mem) <= 500, smoke),
        )

        seek_rows(table, big, scratch, args, ours_wall, ours_mem)
        if args.layouts:
            layout_rows(table, data, scratch, rerun, args)

        if rerun is not None:
            arm_rows(table, data, scratch, rerun, args.arm_minutes, args.rounds, smoke)
        table.print()
        if args.json:
            args.json.write_text(json.dumps(table.figures, indent=2))


def layout_rows(table: Table, data: Path, scratch: Path, rerun: str | None, args: argparse.Namespace) -> None:
    """Every layout of ``bag_layouts`` (issue 48): ``--save`` beside ``rerun mcap convert`` of the same file, the
    layouts and the two commands alternating round by round, outputs deleted and synced before each command."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import bag_layouts

    messages = _Messages(args.seconds)
    events = schedule(args.seconds)
    bags: dict[str, Path] = {}
    for layout in args.layouts:
        if layout in ("rosbags", "db3"):  # the bags the rows above use
            bags[layout] = sensor_bag(data, args.seconds, "db3" if layout == "db3" else "mcap")
        else:
            folder = data / f"sensors_{args.seconds:g}s_{layout}"
            bags[layout] = bag_layouts.layout_bag(folder, layout, events, messages.message, TYPES, messages.ts)
    outs = (scratch / "layout.rrd", scratch / "layout_rerun.rrd")
    runs: dict[tuple[str, str], list[Run]] = {}
    loads = [os.getloadavg()[0]]
    for _ in range(args.rounds):
        for layout, bag in bags.items():
            commands = {"ours": [APP, "--bag", str(bag), "--save", str(outs[0])]}
            if rerun is not None and bag.suffix == ".mcap":  # the converter reads MCAP only
                commands["rerun"] = [rerun, "mcap", "convert", str(bag), "-o", str(outs[1])]
            for name, command in commands.items():
                fresh(*outs)
                runs.setdefault((layout, name), []).append(_checked(run_watched(command), command))
        loads.append(os.getloadavg()[0])
    fresh(*outs)
    table.notes.append(
        f"Layouts ({args.seconds:g} s of bag each; load average {min(loads):.1f}–{max(loads):.1f} over the rounds):\n"
        + "\n".join(f"- {layout}: {bag_layouts.describe(bag)}" for layout, bag in bags.items())
    )
    for layout in bags:
        ours = runs[(layout, "ours")]
        wall, cpu, mem = (_med([getattr(r, k) for r in ours]) for k in ("wall", "cpu", "peak_anon_mb"))
        table.figures |= {f"layout_{layout}_wall_s": wall, f"layout_{layout}_cpu_s": cpu, f"layout_{layout}_mb": mem}
        theirs = runs.get((layout, "rerun"))
        goal = 0.55 if layout.endswith("zstd") else 0.8
        if theirs:
            r_wall, r_cpu, r_mem = (_med([getattr(r, k) for r in theirs]) for k in ("wall", "cpu", "peak_anon_mb"))
            table.figures |= {f"layout_{layout}_rerun_wall_s": r_wall, f"layout_{layout}_rerun_cpu_s": r_cpu}
            table.add(
                f"layout `{layout}` `--save`: wall, CPU, peak RssAnon+RssShmem",
                f"{wall:.1f} s, {cpu:.1f} s, {mem:,.0f} MB",
                f"{r_wall:.1f} s, {r_cpu:.1f} s, {r_mem:,.0f} MB",
                f"{wall / r_wall:.2f}× (CPU {cpu / r_cpu:.2f}×)",
                f"≤ {goal}× and ≤ 300 MB" + _verdict(wall / r_wall <= goal and mem <= 300, args.smoke),
            )
        else:
            table.add(
                f"layout `{layout}` `--save`: wall, CPU, peak RssAnon+RssShmem",
                f"{wall:.1f} s, {cpu:.1f} s, {mem:,.0f} MB",
                "(reads MCAP only)" if rerun is not None else "(no rerun binary)",
                "",
                "≤ 300 MB" + _verdict(mem <= 300, args.smoke),
            )


def seek_rows(
    table: Table, big: Path, scratch: Path, args: argparse.Namespace, full_wall: float, full_mem: float
) -> None:
    """Seek and filter (issue 38): ``--start-offset`` (10 s before the end) against a head run of 2 s
    (``--duration 2``), and the like-for-like seek (``--start-offset … --duration 2``) beside it; ``--topics`` as
    a fraction of the full conversion. The commands alternate, round by round."""
    smoke = args.smoke
    offset = max(0.0, args.seconds - 10.0) if not smoke else args.seconds * 0.8
    head = min(2.0, args.seconds / 2)
    commands = {
        "head": ["--duration", f"{head:g}"],
        "offset": ["--start-offset", f"{offset:g}"],
        "offset_head": ["--start-offset", f"{offset:g}", "--duration", f"{head:g}"],
        "topics": ["--topics", "/scan", "/tf", "/tf_static"],
    }
    runs: dict[str, list[Run]] = {name: [] for name in commands}
    for _ in range(args.rounds):
        for name, flags in commands.items():
            command = [APP, "--bag", str(big), "--save", str(scratch / "part.rrd"), *flags]
            runs[name].append(_checked(run_watched(command), command))
    wall = {name: _med([r.wall for r in rs]) for name, rs in runs.items()}
    cpu = {name: _med([r.cpu for r in rs]) for name, rs in runs.items()}
    mem = {name: _med([r.peak_anon_mb for r in rs]) for name, rs in runs.items()}
    table.figures |= {f"seek_{name}_wall_s": value for name, value in wall.items()}
    table.add(f"`--duration {head:g}` (a head run): wall, CPU", f"{wall['head']:.1f} s, {cpu['head']:.1f} s")
    for name, label in (
        ("offset", f"`--start-offset {offset:g}`"),
        ("offset_head", f"`--start-offset {offset:g} --duration {head:g}`"),
    ):
        ratio = wall[name] / wall["head"]
        table.add(
            f"{label} wall / the head run's (CPU: {cpu[name] / cpu['head']:.2f}×)",
            f"{wall[name]:.1f} s",
            "",
            f"{ratio:.2f}×",
            "≤ 1.5× (issue 38)" + _verdict(ratio <= 1.5, smoke) if name == "offset" else "(the seek alone)",
        )
    fraction = wall["topics"] / full_wall
    table.add(
        "`--topics /scan /tf /tf_static` wall / full `--save`",
        f"{wall['topics']:.1f} s",
        "",
        f"{100 * fraction:.0f} %",
        "≤ 25 %" + _verdict(fraction <= 0.25, smoke),
    )
    for name in ("offset", "topics"):
        table.add(
            f"`{' '.join(commands[name])}`: peak RssAnon (full `--save`: {full_mem:,.0f} MB)",
            f"{mem[name]:,.0f} MB",
            "",
            "",
            "≤ 300 MB (issue 38)" + _verdict(mem[name] <= 300, smoke),
        )


def arm_rows(table: Table, data: Path, scratch: Path, rerun: str, minutes: float, rounds: int, smoke: bool) -> None:
    """The 100 Hz JointState bag of ``benchmarks/bags.py`` (its writer and URDF): work beyond ``import rerun,
    numpy`` over ``rerun mcap convert``."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import bags

    folder = data / f"arm_{minutes:g}min"
    if not (folder / "arm_mcap").exists():
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        bags.write_arm_bags(folder, minutes)
        shutil.rmtree(folder / "arm_db3")
    bag = bags.storage_file(folder / "arm_mcap")
    urdf = bags.chain_urdf(scratch / "arm8.urdf", 8)
    commands = {
        "floor": [PY, "-c", "import rerun, numpy"],
        "ours": [APP, "--bag", str(bag), "--urdf", str(urdf), "--save", str(scratch / "arm.rrd")],
        "rerun": [rerun, "mcap", "convert", str(bag), "-o", str(scratch / "arm_rerun.rrd")],
    }
    runs: dict[str, list[Run]] = {name: [] for name in commands}
    for _ in range(rounds):
        for name, command in commands.items():
            runs[name].append(_checked(run_watched(command), command))
    load = os.getloadavg()[0]
    floor, ours, convert = (_med([r.wall for r in runs[n]]) for n in ("floor", "ours", "rerun"))
    cpu = {n: _med([r.cpu for r in runs[n]]) for n in commands}
    ratio = (ours - floor) / convert
    cpu_ratio = (cpu["ours"] - cpu["floor"]) / cpu["rerun"]
    table.figures |= {"arm_floor_s": floor, "arm_ours_s": ours, "arm_rerun_s": convert}
    table.figures |= {"arm_floor_cpu_s": cpu["floor"], "arm_ours_cpu_s": cpu["ours"], "arm_rerun_cpu_s": cpu["rerun"]}
    table.add(
        f"{minutes:g} min × 100 Hz JointState bag: wall (import floor {floor:.2f} s)",
        f"{ours:.2f} s",
        f"{convert:.2f} s",
        f"{ratio:.2f}× beyond the floor",
        "≤ 2×" + _verdict(ratio <= 2.0, smoke),
    )
    table.add(
        f"… CPU, user + system (import floor {cpu['floor']:.2f} s; load {load:.1f})",
        f"{cpu['ours']:.2f} s",
        f"{cpu['rerun']:.2f} s",
        f"{cpu_ratio:.2f}× beyond the floor",
    )


if __name__ == "__main__":
    main()
