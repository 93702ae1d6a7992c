"""Live ROS 2 through the whole app: ``r2d2-viz --ros --save out.rrd`` against a real Jazzy rclpy node.

Inside a loopback-only network namespace (``unshare -n``: root), a real node (``tests/sources/live/nodes/
publish_sensors.py``, PyPI's rclpy wheels in the tests' cached venv) publishes, once r2d2-viz has subscribed:

1. ``/joint_states`` of a 30-joint chain at 1 kHz (``--seconds``, 60): the share in the recording (rows of
   ``/joints/limited`` / published), the lateness (wall time when the send to Rerun returned − the DDS source
   timestamp, from the app's ``R2D2_VIZ_PACING_LOG`` hook) p50 / p99 / max, and the CPU of the r2d2-viz process
   over the steady part (``/proc/<pid>/stat``) — runs alternating with Rerun's SDK floor: a Python process
   sending one prebuilt 30-row Transform3D chunk per sample with ``rr.send_columns`` at the same rate to the same
   kind of sink (a file). Medians over ``--repeats``.
2. camera and lidar together: 640x480 rgb8 images at 30 Hz, a 640x480 JPEG (CompressedImage) at 30 Hz,
   100,000-point clouds (x y z float32, 1.2 MB) at 10 Hz and 720-ray LaserScans at 20 Hz: the count in the
   recording against the published count, the lateness, and the CPU of r2d2-viz (``--sensors-only``: this alone).

    python benchmarks/live_app.py [--seconds 60] [--repeats 3] [--json out.json]
    python benchmarks/live_app.py --smoke     # a few seconds each, no thresholds (CI; skips without root)
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve()
TESTS = HERE.parents[1] / "tests"
NODE = TESTS / "sources" / "live" / "nodes" / "publish_sensors.py"
PACING_LOG_ENV = "R2D2_VIZ_PACING_LOG"
JOINTS, JOINT_RATE = 30, 1000.0
IMAGE_RATE, CLOUD_RATE, CLOUD_POINTS, JPEG_RATE, SCAN_RATE = 30.0, 10.0, 100_000, 30.0, 20.0
IMAGE, CLOUD, JPEG, SCAN = "/camera/image_raw", "/points", "/camera/image_raw/compressed", "/scan"
BATCH = 20
"""Samples per chunk of the batched SDK floor: what arrives at 1 kHz between two of the app's polls (20 ms)."""


def chain_urdf(joints: int) -> str:
    """A chain of ``joints`` revolute joints (``joint_0`` …), each link a small box."""
    links = [
        f'<link name="link_{i}"><visual><geometry><box size="0.05 0.05 0.1"/></geometry></visual></link>'
        for i in range(joints + 1)
    ]
    chain = [
        f'<joint name="joint_{i}" type="revolute"><parent link="link_{i}"/><child link="link_{i + 1}"/>'
        f'<origin xyz="0 0 0.1"/><axis xyz="{"0 0 1" if i % 2 else "0 1 0"}"/>'
        '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        for i in range(joints)
    ]
    return f'<robot name="chain{joints}">{"".join(links)}{"".join(chain)}</robot>'


def cpu_seconds(pid: int) -> float | None:
    """utime + stime of a running process (Linux /proc)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def cpu_over(pid: int, started: Path | None, window: tuple[float, float], proc: subprocess.Popen[Any]) -> float | None:
    """The share of one core ``pid`` used from ``window[0]`` to ``window[1]`` s after ``started`` has content (or
    after now, ``started`` None)."""
    while started and (not started.exists() or started.stat().st_size == 0) and proc.poll() is None:
        time.sleep(0.005)
    t0 = time.monotonic()
    time.sleep(window[0])
    c0, w0 = cpu_seconds(pid), time.monotonic()
    time.sleep(max(0.0, t0 + window[1] - time.monotonic()))
    c1, w1 = cpu_seconds(pid), time.monotonic()
    return None if c0 is None or c1 is None else (c1 - c0) / (w1 - w0)


def rows_in(rrd: Path, topic: str, *, under: bool = True) -> int:
    """Non-static rows logged at ``topic`` (or under it: a display with Keep > 1 cycles ``topic/<i>``)."""
    from rerun.chunk import RrdReader

    return sum(
        c.num_rows
        for c in RrdReader(rrd).stream()
        if not c.is_static and (c.entity_path == topic or (under and c.entity_path.startswith(topic + "/")))
    )


# --- inside the namespace: the node and r2d2-viz ----------------------------------------------------


def scenario(spec: dict[str, Any]) -> dict[str, Any]:
    """Start the node, then r2d2-viz (it subscribes, the node streams); CPU over the window; the results."""
    tmp = Path(spec["tmp"])
    rrd, log, urdf = tmp / f"{spec['name']}.rrd", tmp / f"{spec['name']}.log", tmp / "chain.urdf"
    log.unlink(missing_ok=True)
    node = subprocess.Popen(
        [spec["ros_python"], str(NODE), "--urdf", str(urdf), "--seconds", str(spec["seconds"]), *spec["node"]],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    exe = Path(sys.executable).parent / "r2d2-viz"
    app_cmd = [str(exe), "--ros", "--urdf", str(urdf), "--save", str(rrd), "--duration", str(spec["seconds"] + 6)]
    app_cmd += ["--video"] if spec.get("video") else []
    app = subprocess.Popen(
        app_cmd, env={**os.environ, PACING_LOG_ENV: str(log)}, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    try:
        window = spec.get("cpu_window")
        # the pacing log is written in blocks: a stream of 90 messages a second fills one late; from the start then
        cpu = cpu_over(app.pid, None if spec.get("cpu_from_start") else log, tuple(window), app) if window else None
        _, app_err = app.communicate(timeout=spec["seconds"] + 90)
        node_out, node_err = node.communicate(timeout=30)
    finally:
        for p in (node, app):
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
                p.wait(timeout=10)
    if app.returncode != 0:
        raise SystemExit(f"r2d2-viz failed ({app.returncode}): {app_err.decode(errors='replace')[-2000:]}")
    lines = node_out.strip().splitlines()
    if not lines:
        raise SystemExit(f"the node failed: {node_err[-2000:]}")
    late: dict[str, list[float]] = {}
    for line in log.read_text().splitlines():
        topic, seconds = line.split()
        late.setdefault(topic, []).append(float(seconds))
    topics = {"/joint_states": "/joints/limited", IMAGE: IMAGE, CLOUD: CLOUD, JPEG: JPEG, SCAN: SCAN}
    sent = json.loads(lines[-1])["sent"]
    received = next((x for x in app_err.decode().splitlines() if x.startswith("r2d2-viz: received")), "")
    out = {"cpu": cpu, "sent": sent, "app_received": received, "in_file": {}, "lateness": late}
    out["in_file"] = {t: rows_in(rrd, topics[t], under=t != "/joint_states") for t in sent}
    if IMAGE in sent and JPEG in sent:  # the JPEGs' entity is under the raw images'
        out["in_file"][IMAGE] -= out["in_file"][JPEG]
    rrd.unlink()
    return out


# --- Rerun's SDK floor ----------------------------------------------------------------------------------


def sdk_floor(rate: float, seconds: float, out: Path, started: Path, per: int = 1) -> None:
    """One prebuilt 30-row Transform3D chunk (the chain's /tf, frame names included) per sample, sent with
    rr.send_columns on an absolute schedule to the app's kind of sink (``sinks.open_recording``, a file);
    ``per`` > 1: one chunk of ``per`` samples every ``per`` samples (batched as the app's 20 ms polls)."""
    import numpy as np
    import pyarrow as pa
    import rerun as rr

    from r2d2_viz.viewer.columns import send
    from r2d2_viz.viewer.sinks import SinkConfig, close_recording, open_recording

    recording = open_recording(SinkConfig(save=out), save_to=out)
    rows, block = JOINTS, 100
    columns = rr.Transform3D.columns(
        translation=np.zeros((rows * block, 3)),
        quaternion=np.tile([0.0, 0.0, 0.0, 1.0], (rows * block, 1)),
        parent_frame=[f"link_{i}" for i in range(rows)] * block,
        child_frame=[f"link_{i + 1}" for i in range(rows)] * block,
    )
    encoded = [(c.component_descriptor(), c.as_arrow_array()) for c in columns]
    started.write_text("started\n")
    start = time.monotonic()
    for k in range(0, round(seconds * rate), per):
        delay = start + k / rate - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        nanos = np.full(rows * per, time.time_ns(), dtype="datetime64[ns]")
        send(recording.rec, "/tf", "timestamp", pa.array(nanos), encoded, (k % (block - per + 1)) * rows, rows * per)
    close_recording(recording)


def floor_cpu(tmp: Path, seconds: float, window: tuple[float, float], per: int = 1) -> float | None:
    out, started = tmp / "floor.rrd", tmp / "floor.started"
    started.unlink(missing_ok=True)
    cmd = [sys.executable, str(HERE), "--sdk-floor", str(JOINT_RATE), str(seconds), str(out), str(started), str(per)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    cpu = cpu_over(proc.pid, started, window, proc)
    _, err = proc.communicate(timeout=seconds + 60)
    if proc.returncode != 0:
        raise SystemExit(f"the SDK floor failed: {err.decode(errors='replace')[-2000:]}")
    out.unlink(missing_ok=True)
    return cpu


# --- the driver -----------------------------------------------------------------------------------------


def in_namespace(spec: dict[str, Any]) -> dict[str, Any]:
    sys.path.insert(0, str(TESTS))
    from sources.live import ros_node

    command = [sys.executable, str(HERE), "--scenario", json.dumps(spec)]
    done = ros_node.in_netns(command, timeout=spec["seconds"] + 150)
    if done.returncode != 0:
        raise SystemExit(f"live_app: the scenario failed: {done.stderr[-3000:]}")
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def pct(xs: list[float], skip: int = 0) -> str:
    import numpy as np

    a = np.array(xs[skip:] or xs) * 1e3
    return f"{np.percentile(a, 50):.2f} / {np.percentile(a, 99):.2f} / {a.max():.2f} ms"


def p99(xs: list[float], skip: int = 0) -> float:
    import numpy as np

    return float(np.percentile(np.array(xs[skip:] or xs) * 1e3, 99))


def med(xs: list[float]) -> float:
    return float(statistics.median(xs))


def main() -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="a few seconds each, for CI; no thresholds")
    parser.add_argument("--seconds", type=float, default=60.0, help="the 1 kHz joint-state stream")
    parser.add_argument("--sensor-seconds", type=float, default=20.0, help="the image + cloud stream")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--distro", default="jazzy", choices=["jazzy", "kilted"])
    parser.add_argument("--json", type=Path)
    parser.add_argument("--sensors-only", action="store_true", help="only the camera and lidar run (2.)")
    parser.add_argument("--video", action="store_true", help="the app with --video (the camera encoded as it arrives)")
    parser.add_argument("--scenario", help=argparse.SUPPRESS)
    parser.add_argument("--sdk-floor", nargs=5, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.scenario:
        print(json.dumps(scenario(json.loads(args.scenario))))
        return 0
    if args.sdk_floor:
        rate, seconds, out, started, per = args.sdk_floor
        sdk_floor(float(rate), float(seconds), Path(out), Path(started), int(per))
        return 0
    sys.path.insert(0, str(TESTS))
    from sources.live import ros_node

    missing = ros_node.netns_missing()
    if missing:
        print(f"live_app: skipped: {missing}")
        return 0
    if args.smoke:
        args.seconds, args.sensor_seconds, args.repeats = 6.0, 3.0, 1
    python = str(ros_node.ensure_venv(args.distro))
    window = (2.0, args.seconds - 3.0) if not args.smoke else (1.0, 3.0)
    figures: dict[str, Any] = {"window_s": window}
    with tempfile.TemporaryDirectory(prefix="r2d2-live-app-") as tmp_name:
        tmp = Path(tmp_name)
        (tmp / "chain.urdf").write_text(chain_urdf(JOINTS))
        base = {"tmp": tmp_name, "ros_python": python}
        joint_runs, floors, batched = [], [], []
        (tmp / "cam.jpg").write_bytes(jpeg_bytes())
        for _ in range(0 if args.sensors_only else args.repeats):
            node = ["--joints", str(JOINTS), "--joint-rate", str(JOINT_RATE)]
            spec = {**base, "name": "joints", "seconds": args.seconds, "node": node, "cpu_window": window}
            joint_runs.append(in_namespace(spec))
            floors.append(floor_cpu(tmp, args.seconds, window))
            batched.append(floor_cpu(tmp, args.seconds, window, per=BATCH))
        node = ["--image-rate", str(IMAGE_RATE), "--cloud-rate", str(CLOUD_RATE), "--cloud-points", str(CLOUD_POINTS),
                "--cloud-fields", "xyz", "--compressed-rate", str(JPEG_RATE), "--jpeg", str(tmp / "cam.jpg"),
                "--scan-rate", str(SCAN_RATE)]  # fmt: skip
        # from the app's start: it subscribes within ~2 s, the node then streams for --sensor-seconds
        sensor_window = (4.0, args.sensor_seconds) if not args.smoke else (2.0, 3.0)
        spec = {**base, "name": "sensors", "seconds": args.sensor_seconds, "node": node, "cpu_window": sensor_window,
                "cpu_from_start": True, "video": args.video}  # fmt: skip
        figures["sensor_window_s"] = sensor_window
        sensors = in_namespace(spec)
    figures["floor_batched_cpu"] = batched
    report(args, joint_runs, floors, sensors, figures)
    if args.json:
        args.json.write_text(json.dumps(figures, indent=1))
    return 0


def jpeg_bytes() -> bytes:
    """A real 640x480 JPEG (Pillow, quality 80) of a gradient."""
    import io

    import numpy as np
    from PIL import Image

    yy, xx = np.indices((480, 640))
    rgb = np.stack([xx % 256, yy % 256, (xx + yy) % 256], axis=2).astype(np.uint8)
    out = io.BytesIO()
    Image.fromarray(rgb).save(out, format="JPEG", quality=80)
    return out.getvalue()


def report_joints(
    args: argparse.Namespace, runs: list[dict[str, Any]], floors: list[float | None], figures: dict[str, Any]
) -> None:
    js = "/joint_states"
    skip = int(2 * JOINT_RATE)  # the first 2 s: what arrived while the app settled is handed over at once
    share = [r["in_file"][js] / r["sent"][js] for r in runs]
    cpu = [r["cpu"] for r in runs if r["cpu"] is not None]
    floor = [f for f in floors if f is not None]
    print(f"1. /joint_states, {JOINTS} joints at {JOINT_RATE:g} Hz for {args.seconds:g} s, {len(runs)} run(s)"
          f" ({'smoke: no thresholds' if args.smoke else 'goals in brackets'})")  # fmt: skip
    for i, r in enumerate(runs):
        lat = r["lateness"][js]
        print(f"   run {i + 1}: {r['in_file'][js]}/{r['sent'][js]} in the recording ({100 * share[i]:.2f} %);"
              f" lateness p50/p99/max all {pct(lat)}, after the first 2 s {pct(lat, skip)};"
              f" CPU {100 * (r['cpu'] or 0):.1f} % ; {r['app_received']}")  # fmt: skip
    p99_all = med([p99(r["lateness"][js]) for r in runs])
    p99_steady = med([p99(r["lateness"][js], skip) for r in runs])
    print(f"   median share {100 * med(share):.2f} % [>= 99.5 %]; median p99 lateness {p99_all:.2f} ms,"
          f" after the first 2 s {p99_steady:.2f} ms [<= 5 ms]")  # fmt: skip
    if cpu and floor:
        beyond = med(cpu) - med(floor)
        print(f"   CPU {window_text(figures)}: r2d2-viz {100 * med(cpu):.1f} % of a core, Rerun SDK floor"
              f" {100 * med(floor):.1f} % (runs {', '.join(f'{100 * f:.1f}' for f in floor)}); beyond the floor"
              f" {100 * beyond:.1f} % [<= 10 %]")  # fmt: skip
    batched = [f for f in figures["floor_batched_cpu"] if f is not None]
    if cpu and batched:
        print(f"   the SDK floor batched as the app sends ({BATCH} samples a chunk every {BATCH} ms):"
              f" {100 * med(batched):.1f} % (runs {', '.join(f'{100 * f:.1f}' for f in batched)}); the app beyond it"
              f" {100 * (med(cpu) - med(batched)):.1f} %")  # fmt: skip


def report(
    args: argparse.Namespace,
    runs: list[dict[str, Any]],
    floors: list[float | None],
    sensors: dict[str, Any],
    figures: dict[str, Any],
) -> None:
    js = "/joint_states"
    skip = int(2 * JOINT_RATE)
    if runs:
        report_joints(args, runs, floors, figures)
    print(f"2. images 640x480 rgb8 at {IMAGE_RATE:g} Hz + JPEGs at {JPEG_RATE:g} Hz + {CLOUD_POINTS:,}-point"
          f" clouds (xyz) at {CLOUD_RATE:g} Hz + scans at {SCAN_RATE:g} Hz, {args.sensor_seconds:g} s")  # fmt: skip
    for topic in (IMAGE, JPEG, CLOUD, SCAN):
        lat = sensors["lateness"].get(topic, [])
        sent, got = sensors["sent"][topic], sensors["in_file"][topic]
        print(f"   {topic}: {got}/{sent} in the recording ({100 * got / sent:.1f} %); lateness"
              f" p50/p99/max {pct(lat) if lat else '-'} [p99 <= 50 ms]")  # fmt: skip
    if sensors["cpu"] is not None:
        a, b = figures["sensor_window_s"]
        print(f"   CPU of r2d2-viz: {100 * sensors['cpu']:.1f} % of a core ({a:g}-{b:g} s after its start)")
    print(f"   {sensors['app_received']}")
    figures.update(
        joints=[{k: v for k, v in r.items() if k != "lateness"} | {
            "lateness_ms_p99": p99(r["lateness"][js]), "lateness_ms_p99_after_2s": p99(r["lateness"][js], skip)}
            for r in runs],
        floor_cpu=floors,
        sensors={k: v for k, v in sensors.items() if k != "lateness"} | {
            "lateness_ms_p99": {t: p99(x) for t, x in sensors["lateness"].items()}},
    )  # fmt: skip


def window_text(figures: dict[str, Any]) -> str:
    a, b = figures["window_s"]
    return f"{a:g}-{b:g} s after the first message handed over"


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
