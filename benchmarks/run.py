#!/usr/bin/env python3
"""Performance benchmarks of r2d2-viz (issue #4): one script, one table.

    python benchmarks/run.py               # full run (~8 min on 2 cores)
    python benchmarks/run.py --smoke       # tiny sizes, for CI (well under a minute); no thresholds
    python benchmarks/run.py --json out.json

Whole-command figures (wall time, CPU time, peak RSS) are measured on subprocesses of the installed
app with ``os.wait4`` (no /usr/bin/time, no psutil). Every ratio compares numbers measured in this
run, side by side (the import floor and the batch run alternate), as medians over repeats. The
machine may be shared: medians, not minima, are reported. Goals are printed next to the figures for
information only: the script never fails on a threshold.

Run it with the Python of the environment the app is installed in (``pip install .``); it must not
be run from inside the package's source tree on ``sys.path`` (it is not: only ``benchmarks/`` is).
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import os
import platform
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

PY = sys.executable
APP = [PY, "-m", "r2d2_viz"]
IMPORT_FLOOR = [PY, "-c", "import rerun, numpy"]
"""What any Python program that logs to Rerun imports (the app's own floor: it reads URDFs with lxml, and imports
trimesh only to convert mesh files)."""
RATE = 30.0
ROBOT_BLOCK_SAMPLES = 150
ROBOT_BLOCKS = 5
"""Per-sample robot figures: the median over this many chunks of ROBOT_BLOCK_SAMPLES samples (a live block at
30 Hz: five seconds), in each repeat."""
PACING_LOG_ENV = "R2D2_VIZ_PACING_LOG"


@dataclass(frozen=True)
class Sizes:
    batch_seconds: float  # goal 1: 3600 s = 108,000 samples
    repeats: int
    rrlog_samples: int  # rr.log baseline, extrapolated per sample
    kin_samples: int
    kin_repeats: int
    memory_seconds: float  # goal 3: 86,400 s = 2.6 M samples
    live_seconds: float  # goal 4: count samples sent after this many seconds at 30 Hz
    cpu_window: tuple[float, float]  # seconds after the first sample
    cpu_repeats: int  # 30 Hz CPU: runs of the app and of the Rerun SDK floor, alternating
    fast_rate: float
    fast_seconds: float
    robot_sizes: tuple[int, ...]
    robot_repeats: int
    size_seconds: float  # goal 6: the default recording (one 48 s lap)


FULL = Sizes(3600, 5, 3000, 100_000, 7, 86_400, 60, (5.0, 35.0), 3, 1000, 20, (10, 100, 1000, 3000), 5, 48)
"""The sizes the issue names."""
SMOKE = Sizes(60, 1, 60, 2_000, 2, 600, 3, (1.0, 2.5), 1, 1000, 1, (10, 100), 1, 4)


# --- measuring ---------------------------------------------------------------------------------------


@dataclass
class Proc:
    wall: float
    cpu: float
    max_rss_mb: float
    returncode: int
    stderr: str = ""


def run_cmd(cmd: Sequence[str], *, cwd: Path, env: dict[str, str] | None = None) -> Proc:
    """Run to completion; wall clock around the whole process, CPU and peak RSS from wait4."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    assert proc.stderr is not None
    err = proc.stderr.read().decode(errors="replace")  # small: the app writes a few lines
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{err}")
    return Proc(wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, proc.returncode, err)


def median(xs: Sequence[float]) -> float:
    return float(statistics.median(xs))


def _proc_cpu_seconds(pid: int) -> float | None:
    """utime + stime of a running process, from /proc (Linux); None elsewhere."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


# --- rr.log baseline (runs in a subprocess: `run.py --rrlog-baseline N OUT`) ---------------------------


def rrlog_baseline(n_samples: int, out: Path) -> None:
    """Log the default recording's per-sample data with ``rr.log``, one call per entity per sample.

    Same entities, components and values as the app (transforms with frame names, TF arrows, joint
    values). Kinematics are computed beforehand and not timed; only the logging loop and the final
    flush are. Prints seconds per sample."""
    import rerun as rr

    from r2d2_viz.kinematics.tree import compile_tree, joint_transforms, moving_values
    from r2d2_viz.robot.model import default_urdf_path, load_urdf
    from r2d2_viz.sources.motion import ODOM, make_motion
    from r2d2_viz.viewer.entities import TIMELINE, path

    robot = load_urdf(default_urdf_path())
    tree = compile_tree(robot)
    motion = make_motion(robot, n_samples=n_samples)
    chunk = next(motion.chunks(n_samples))
    q = chunk.positions[:, [motion.joints.index(a) for a in tree.actuated]]
    values = moving_values(tree, q)
    translation, quat = joint_transforms(tree, q)
    joints = [robot.joint(name) for name in tree.moving]
    limits = tree.limits
    value_paths = [
        path("joints", "limited", j.name, "value") if j.name in limits else path("joints", "continuous", j.name)
        for j in joints
    ]
    odom = chunk.frames[0]  # odom → root
    rec = rr.RecordingStream("r2d2_viz_rrlog_baseline")
    rec.save(out)
    t0 = time.perf_counter()
    for k in range(n_samples):
        rec.set_time(TIMELINE, duration=k / RATE)
        for m, j in enumerate(joints):
            rec.log(
                path("tf", j.child),
                rr.Transform3D(
                    translation=translation[k, m],
                    quaternion=rr.Quaternion(xyzw=quat[k, m]),
                    parent_frame=j.parent,
                    child_frame=j.child,
                ),
            )
            if j.type == "prismatic":
                rec.log(
                    path("tf_arrows", j.child), rr.Arrows3D(origins=[translation[k, m]], vectors=[-translation[k, m]])
                )
        t, qo = odom.translation[k], odom.quat_xyzw[k]
        rec.log(
            path("tf", robot.root),
            rr.Transform3D(translation=t, quaternion=rr.Quaternion(xyzw=qo), parent_frame=ODOM, child_frame=robot.root),
        )
        rec.log(path("tf_arrows", robot.root), rr.Arrows3D(origins=[t], vectors=[-t]))
        for m in range(len(joints)):
            rec.log(value_paths[m], rr.Scalars(values[k, m]))
    rec.flush()
    print((time.perf_counter() - t0) / n_samples)


# --- the goals ---------------------------------------------------------------------------------------


@dataclass
class Report:
    rows: list[tuple[str, str, str, str]] = field(default_factory=list)  # figure, value, goal, verdict
    figures: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def add(self, figure: str, value: str, goal: str = "", met: bool | None = None) -> None:
        verdict = "" if met is None else ("met" if met else "NOT met")
        self.rows.append((figure, value, goal, verdict))

    def section(self, title: str) -> None:
        self.rows.append((f"**{title}**", "", "", ""))


def bench_batch(s: Sizes, tmp: Path, r: Report) -> float:
    """Goal 1: batch run vs its import floor (alternating) and vs rr.log sample by sample."""
    out = tmp / "batch.rrd"
    floor: list[Proc] = []
    batch: list[Proc] = []
    for _ in range(s.repeats):
        floor.append(run_cmd(IMPORT_FLOOR, cwd=tmp))
        batch.append(run_cmd([*APP, "--save", str(out), "--duration", str(s.batch_seconds)], cwd=tmp))
    samples = round(s.batch_seconds * RATE)
    f_wall, b_wall = median([p.wall for p in floor]), median([p.wall for p in batch])
    f_cpu, b_cpu = median([p.cpu for p in floor]), median([p.cpu for p in batch])
    work = max(b_wall - f_wall, 1e-9)

    baseline = subprocess.run(
        [PY, __file__, "--rrlog-baseline", str(s.rrlog_samples), str(tmp / "rrlog.rrd")],
        cwd=tmp,
        capture_output=True,
        text=True,
        check=True,
    )
    rrlog_per_sample = float(baseline.stdout.split()[-1])
    rrlog_total = rrlog_per_sample * samples
    ratio_floor = b_wall / f_wall
    speedup = rrlog_total / work
    r.section(f"1. Batch: --save --duration {s.batch_seconds:g} ({samples:,} samples), medians of {s.repeats}")
    r.add("import floor (rerun, numpy): wall / CPU", f"{f_wall:.2f} s / {f_cpu:.2f} s")
    r.add("r2d2-viz batch run: wall / CPU", f"{b_wall:.2f} s / {b_cpu:.2f} s")
    r.add("batch wall / import floor wall", f"{ratio_floor:.2f}×", "≤ 1.5×", ratio_floor <= 1.5)
    r.add("  work beyond the floor (batch − floor)", f"{work:.2f} s = {samples / work:,.0f} samples/s")
    r.add(
        f"rr.log sample by sample (measured on {s.rrlog_samples:,} samples, extrapolated)",
        f"{rrlog_per_sample * 1e6:.0f} µs/sample → {rrlog_total:.1f} s",
    )
    r.add("rr.log time / batch work beyond the floor", f"{speedup:,.0f}×", "≥ 100×", speedup >= 100)
    r.add("rr.log time / whole batch command", f"{rrlog_total / b_wall:,.0f}×")
    r.figures["batch"] = {
        "samples": samples,
        "floor_wall_s": [p.wall for p in floor],
        "batch_wall_s": [p.wall for p in batch],
        "floor_cpu_s": [p.cpu for p in floor],
        "batch_cpu_s": [p.cpu for p in batch],
        "batch_max_rss_mb": [p.max_rss_mb for p in batch],
        "ratio_batch_to_floor": ratio_floor,
        "rrlog_s_per_sample": rrlog_per_sample,
        "rrlog_samples_measured": s.rrlog_samples,
        "speedup_vs_rrlog": speedup,
    }
    return median([p.max_rss_mb for p in batch])


def bench_kinematics(s: Sizes, r: Report) -> None:
    """Goal 2: joint_transforms vs Rerun's UrdfJoint.compute_transform_columns, same joint values."""
    import numpy as np
    from rerun.urdf import UrdfTree

    from r2d2_viz.kinematics.tree import compile_tree, joint_transforms
    from r2d2_viz.robot.model import default_urdf_path, load_urdf
    from r2d2_viz.sources.motion import make_motion

    robot = load_urdf(default_urdf_path())
    tree = compile_tree(robot)
    motion = make_motion(robot, n_samples=s.kin_samples)
    chunk = next(motion.chunks(s.kin_samples))
    q = np.ascontiguousarray(chunk.positions[:, [motion.joints.index(a) for a in tree.actuated]])
    urdf = UrdfTree.from_file_path(default_urdf_path())
    rr_joints = [urdf.get_joint_by_name(name) for name in tree.moving]
    columns = [tree.actuated.index(name) for name in tree.moving]  # the R2D2 has no mimic joints
    lists = [q[:, c].tolist() for c in columns]  # Rerun takes Python lists: built outside the timing

    def ours() -> None:
        joint_transforms(tree, q)

    def rerun_public() -> None:
        for joint, values in zip(rr_joints, lists, strict=True):
            assert joint is not None
            joint.compute_transform_columns(values, clamp=False)

    # same values, same results (Rerun: float lists; ours: float64 arrays)
    t_ours, q_ours = joint_transforms(tree, q)
    for m, (joint, values) in enumerate(zip(rr_joints, lists, strict=True)):
        assert joint is not None
        res = {
            str(c.component_descriptor()).split(":")[-1]: c.as_arrow_array()
            for c in joint.compute_transform_columns(values[:50], clamp=False)
        }
        t_rr = np.asarray(res["translation"].flatten().flatten()).reshape(-1, 3)
        q_rr = np.asarray(res["quaternion"].flatten().flatten()).reshape(-1, 4)
        assert np.allclose(t_rr, t_ours[:50, m], atol=1e-6)
        sign = np.sign(np.sum(q_rr * q_ours[:50, m], axis=-1, keepdims=True))
        assert np.allclose(q_rr * sign, q_ours[:50, m], atol=1e-6)

    times: dict[str, list[float]] = {"ours": [], "rerun_public": []}
    for _ in range(s.kin_repeats):  # alternate, so a busy moment hits all three alike
        for name, fn in (("ours", ours), ("rerun_public", rerun_public)):
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    rate = {k: s.kin_samples / median(v) for k, v in times.items()}
    ratio = rate["ours"] / rate["rerun_public"]
    r.section(f"2. Kinematics: R2D2, {s.kin_samples:,} samples of the tutorial motion, medians of {s.kin_repeats}")
    r.add("r2d2_viz joint_transforms (numpy, all moving joints)", f"{rate['ours']:,.0f} samples/s")
    r.add("Rerun UrdfJoint.compute_transform_columns (its public API)", f"{rate['rerun_public']:,.0f} samples/s")
    r.add("ours / Rerun", f"{ratio:.1f}×", "≥ 3×", ratio >= 3)
    r.figures["kinematics"] = {"samples": s.kin_samples, "seconds": times, "samples_per_s": rate, "ratio": ratio}


def bench_memory(s: Sizes, tmp: Path, r: Report, batch_rss_mb: float) -> None:
    """Goal 3: peak RSS of a 24 h batch run."""
    p = run_cmd([*APP, "--save", str(tmp / "day.rrd"), "--duration", str(s.memory_seconds)], cwd=tmp)
    samples = round(s.memory_seconds * RATE)
    size_mb = (tmp / "day.rrd").stat().st_size / 1e6
    (tmp / "day.rrd").unlink()
    r.section(f"3. Memory: --save --duration {s.memory_seconds:g} ({samples:,} samples)")
    r.add("peak RSS", f"{p.max_rss_mb:.0f} MB (1 h run: {batch_rss_mb:.0f} MB)", "< 400 MB", p.max_rss_mb < 400)
    r.add("wall / file size", f"{p.wall:.1f} s / {size_mb:.0f} MB")
    r.figures["memory"] = {"samples": samples, "max_rss_mb": p.max_rss_mb, "wall_s": p.wall, "file_mb": size_mb}


def _live_run(
    tmp: Path, rate: float, seconds: float, cpu_window: tuple[float, float] | None, *, sdk_floor: bool = False
) -> tuple[list[tuple[int, float]], float | None, int]:
    """A real --realtime run with the pacing log; CPU sampled from /proc over a window after start-up.

    ``sdk_floor``: instead of the app, :func:`sdk_floor` (Rerun's SDK alone, paced and saved the same way)."""
    log = tmp / f"pacing_{rate:g}.txt"
    out = tmp / f"live_{rate:g}.rrd"
    log.unlink(missing_ok=True)
    env = {**os.environ, PACING_LOG_ENV: str(log)}
    if sdk_floor:
        cmd = [PY, str(Path(__file__).resolve()), "--sdk-floor", str(rate), str(seconds), str(out)]
    else:
        cmd = [*APP, "--save", str(out), "--realtime", "--rate", str(rate), "--duration", str(seconds)]
    proc = subprocess.Popen(cmd, cwd=tmp, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    cpu_fraction = None
    try:
        if cpu_window is not None:
            while not log.exists():  # opened just before the first sample: start-up is over
                if proc.poll() is not None:
                    break
                time.sleep(0.01)
            t_first = time.monotonic()
            time.sleep(cpu_window[0])
            c0, w0 = _proc_cpu_seconds(proc.pid), time.monotonic()
            time.sleep(max(0.0, cpu_window[1] - (time.monotonic() - t_first)))
            c1, w1 = _proc_cpu_seconds(proc.pid), time.monotonic()
            if c0 is not None and c1 is not None:
                cpu_fraction = (c1 - c0) / (w1 - w0)
        if proc.wait(timeout=seconds + 120) != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed")
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            proc.wait()
    rows = [(int(a), float(b)) for a, b in (line.split() for line in log.read_text().splitlines())]
    in_file = 0 if sdk_floor else _count_rows(out, "/joints/limited")  # one row per sample
    out.unlink()
    return rows, cpu_fraction, in_file


def _median_or_none(xs: Sequence[float | None]) -> float | None:
    known = [x for x in xs if x is not None]
    return median(known) if known else None


def sdk_floor(rate: float, seconds: float, out: Path) -> None:
    """The least a live sample costs through Rerun's SDK: the app's sink (``sinks.open_recording``, live), the
    app's absolute schedule, one prebuilt 4-row ``Transform3D`` chunk per sample (the R2D2's ``/tf``: three
    joints and odom → root, frame names included) sent with rr.send_columns, as the app sends — no kinematics, plots,
    arrows or limit lines. Writes the same pacing log as the app (``R2D2_VIZ_PACING_LOG``)."""
    import numpy as np
    import pyarrow as pa
    import rerun as rr

    from r2d2_viz.viewer.columns import send
    from r2d2_viz.viewer.sinks import SinkConfig, close_recording, open_recording

    recording = open_recording(SinkConfig(save=out), save_to=out)
    rows, block = 4, max(1, round(rate))
    columns = rr.Transform3D.columns(
        translation=np.zeros((rows * block, 3)),
        quaternion=np.tile([0.0, 0.0, 0.0, 1.0], (rows * block, 1)),
        parent_frame=["base", "body", "head", "odom"] * block,
        child_frame=["body", "head", "rod", "base"] * block,
    )
    encoded = [(c.component_descriptor(), c.as_arrow_array()) for c in columns]
    n_samples = max(1, round(seconds * rate))
    with open(os.environ[PACING_LOG_ENV], "w") as log:
        start = time.monotonic()
        for k in range(n_samples):
            delay = start + k / rate - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            i = k % block
            nanos = np.full(rows, round(k / rate * 1e9), dtype="timedelta64[ns]")
            send(recording.rec, "/tf", "time", pa.array(nanos), encoded, i * rows, rows)  # rr.send_columns
            log.write(f"{k} {time.monotonic() - (start + k / rate):.6f}\n")
    close_recording(recording)


def _count_rows(rrd: Path, entity: str) -> int:
    from rerun.chunk import RrdReader

    return sum(c.num_rows for c in RrdReader(rrd).stream() if c.entity_path == entity and not c.is_static)


def bench_live(s: Sizes, tmp: Path, r: Report) -> None:
    """Goal 4: absolute schedule, lateness at 1 kHz, CPU at 30 Hz, through the real app (--realtime)."""
    import numpy as np

    horizon = s.live_seconds
    rows, cpu, in_file = _live_run(tmp, RATE, horizon + 2, s.cpu_window)
    cpu_runs, floor_runs = [cpu], []
    for k in range(s.cpu_repeats):  # alternating: the app, then the SDK alone, in the same conditions
        floor_runs.append(_live_run(tmp, RATE, s.cpu_window[1] + 2, s.cpu_window, sdk_floor=True)[1])
        if k + 1 < s.cpu_repeats:
            cpu_runs.append(_live_run(tmp, RATE, s.cpu_window[1] + 2, s.cpu_window)[1])
    # sample k is due at k / rate after the schedule's start; its send returned `lateness` later
    sent_by = sum(1 for k, late in rows if k / RATE + late <= horizon)
    due_by = math.floor(horizon * RATE) + 1  # samples 0 … 30·T are due at T (inclusive)
    late30 = np.array([late for _, late in rows]) * 1e3
    fast, _, fast_in_file = _live_run(tmp, s.fast_rate, s.fast_seconds, None)
    late = np.array([late for _, late in fast]) * 1e3
    p50, p99, worst = (float(np.percentile(late, p)) for p in (50, 99, 100))
    r.section("4. Live: r2d2-viz --save X --realtime (paced to the wall clock), pacing log")
    r.add(
        f"samples sent {horizon:g} s after the first, at 30 Hz",
        f"{sent_by} (due: {due_by}; in file: {in_file} of {len(rows)})",
        f"{round(horizon * RATE)} ± 1",
        abs(sent_by - round(horizon * RATE)) <= 1,
    )
    r.add(
        "lateness at 30 Hz: p50 / p99 / max",
        f"{np.percentile(late30, 50):.2f} / {np.percentile(late30, 99):.2f} / {late30.max():.2f} ms",
    )
    r.add(
        f"lateness at {s.fast_rate:g} Hz ({len(fast):,} samples): p50 / p99 / max",
        f"{p50:.2f} / {p99:.2f} / {worst:.2f} ms",
        "p99 ≤ 2 ms",
        p99 <= 2.0,
    )
    cpu = _median_or_none(cpu_runs)
    floor = _median_or_none(floor_runs)
    if cpu is not None:
        r.add(
            f"CPU at 30 Hz, {s.cpu_window[0]:g}–{s.cpu_window[1]:g} s after the first sample, median of "
            f"{len(cpu_runs)} runs",
            f"{cpu * 100:.2f} % of one core (runs: {', '.join(f'{c * 100:.2f}' for c in cpu_runs if c is not None)})",
            "≤ 3 %",
            cpu <= 0.03,
        )
    if floor is not None:
        r.add(
            "  Rerun's SDK alone, same pacing and sink: one 4-row Transform3D chunk a sample, median of "
            f"{len(floor_runs)}",
            f"{floor * 100:.2f} % (runs: {', '.join(f'{c * 100:.2f}' for c in floor_runs if c is not None)})",
        )
        if cpu is not None:
            r.add(
                "  the app beyond that floor",
                f"{(cpu - floor) * 100:.2f} % = {(cpu - floor) / RATE * 1e6:.0f} µs a sample",
            )
    r.figures["live"] = {
        "seconds": horizon,
        "samples_sent_by_horizon": sent_by,
        "samples_in_file": in_file,
        "lateness_30hz_ms_p50_p99_max": [
            float(np.percentile(late30, 50)),
            float(np.percentile(late30, 99)),
            float(late30.max()),
        ],
        "fast_rate": s.fast_rate,
        "fast_samples": len(fast),
        "fast_samples_in_file": fast_in_file,
        "lateness_fast_ms_p50_p99_max": [p50, p99, worst],
        "cpu_fraction_30hz": cpu,
        "cpu_fraction_30hz_runs": cpu_runs,
        "sdk_floor_cpu_fraction_30hz_runs": floor_runs,
        "cpu_window_s": list(s.cpu_window),
    }


def bench_robots(s: Sizes, tmp: Path, r: Report) -> None:
    """Goal 5: generated chains and trees; load, first sample, per-sample cost vs number of links."""
    import rerun as rr

    from r2d2_viz.kinematics.tree import compile_tree, joint_transforms
    from r2d2_viz.robot.model import load_urdf
    from r2d2_viz.robot.synth import random_urdf
    from r2d2_viz.sources.motion import make_motion
    from r2d2_viz.viewer.stream import RobotStream

    types = ("fixed", "revolute", "continuous", "prismatic")
    table: dict[str, dict[int, dict[str, float]]] = {}
    cases = [(shape, n) for shape in ("chain", "tree") for n in s.robot_sizes]
    runs_of: dict[tuple[str, int], dict[str, list[float]]] = {}
    moving_of: dict[tuple[str, int], int] = {}
    for shape, n in cases:
        (tmp / f"{shape}_{n}.urdf").write_text(random_urdf(n, seed=n, chain=shape == "chain", joint_types=types))
        runs_of[shape, n] = {"load": [], "static": [], "first": [], "sample": [], "fk": []}
    for _ in range(s.robot_repeats):  # every size once per repeat: a slow spell of the machine hits them all
        for shape, n in cases:
            urdf = tmp / f"{shape}_{n}.urdf"
            runs = runs_of[shape, n]
            t0 = time.perf_counter()
            tree = compile_tree(load_urdf(urdf))
            t1 = time.perf_counter()
            rec = rr.RecordingStream("bench")
            rec.save(tmp / "robot.rrd")
            motion = make_motion(tree.robot, rate=RATE)
            stream = RobotStream(rec, tree, frames=motion.frames, clock=motion.clock, warn=lambda _: None)
            stream.log_static()
            t2 = time.perf_counter()
            chunks = motion.chunks(1)
            stream.send(stream.prepare(next(chunks)))
            t3 = time.perf_counter()
            moving = len(tree.moving)
            block = ROBOT_BLOCK_SAMPLES  # the same chunk length for every size, as live runs have
            per_sample, per_sample_fk = [], []
            fresh = make_motion(tree.robot, rate=RATE, n_samples=block * ROBOT_BLOCKS)  # from sample 0
            for chunk in fresh.chunks(block):
                t4 = time.perf_counter()
                stream.send(stream.prepare(chunk))
                t5 = time.perf_counter()
                joint_transforms(tree, chunk.positions)
                t6 = time.perf_counter()
                per_sample.append((t5 - t4) / block)
                per_sample_fk.append((t6 - t5) / block)
            rec.flush()
            rec.disconnect()
            # Free this case now, outside the timed regions: otherwise the next case's `tree = …` would
            # pay for dropping this one's (a bias that grows with the previous size).
            del tree, stream, rec, chunks, chunk, motion, fresh
            gc.collect()
            runs["load"].append(t1 - t0)
            runs["static"].append(t2 - t1)
            runs["first"].append(t3 - t2)
            runs["sample"].append(median(per_sample))
            runs["fk"].append(median(per_sample_fk))
            moving_of[shape, n] = moving
    for shape, n in cases:
        table.setdefault(shape, {})[n] = {k: median(v) for k, v in runs_of[shape, n].items()}
        table[shape][n] |= {"moving": moving_of[shape, n]}
    r.section(f"5. Generated robots ({'/'.join(types)} joints, 15 % mimic), medians of {s.robot_repeats}")
    r.add(
        f"links: shape (per sample: median of {ROBOT_BLOCKS} chunks of {ROBOT_BLOCK_SAMPLES} samples)",
        "load | static | first sample | per sample (log) | per sample (FK)",
    )
    for shape, by_n in table.items():
        for n, f in by_n.items():
            r.add(
                f"{n:>5} links: {shape} ({f['moving']:.0f} moving joints)",
                f"{f['load'] * 1e3:.1f} ms | {f['static'] * 1e3:.1f} ms | {f['first'] * 1e3:.2f} ms | "
                f"{f['sample'] * 1e6:.1f} µs | {f['fk'] * 1e6:.2f} µs",
            )
    lo, hi = s.robot_sizes[-2] if len(s.robot_sizes) > 2 else s.robot_sizes[0], s.robot_sizes[-1]
    worst = 0.0
    for shape, by_n in table.items():
        exps = []
        for key in ("load", "static", "first", "sample", "fk"):
            exp = math.log(by_n[hi][key] / by_n[lo][key]) / math.log(hi / lo)
            exps.append(f"{key} {exp:.2f}")
            worst = max(worst, exp)
        r.add(f"growth exponent {lo}→{hi} links, {shape}", ", ".join(exps))
    r.add("largest growth exponent (1 = linear)", f"{worst:.2f}", "≤ ~1 (linear)", worst <= 1.15)
    r.figures["robots"] = {"joint_types": types, "table": table, "worst_exponent": worst, "between": [lo, hi]}


def bench_size(s: Sizes, tmp: Path, r: Report) -> None:
    """Goal 6: bytes per sample of the default recording, and what is per sample."""
    from rerun.chunk import RrdReader

    files = {}
    for seconds in (s.size_seconds, 2 * s.size_seconds):
        out = tmp / f"size_{seconds:g}.rrd"
        args = [] if seconds == 48 else ["--duration", str(seconds)]
        run_cmd([*APP, "--save", str(out), *args], cwd=tmp)
        files[seconds] = out.stat().st_size
    samples = round(s.size_seconds * RATE)
    per_sample = (files[2 * s.size_seconds] - files[s.size_seconds]) / samples
    static_bytes = files[s.size_seconds] - per_sample * samples
    temporal: dict[str, dict[str, int]] = {}
    rows: dict[str, int] = {}
    static_entities = set()
    for chunk in RrdReader(tmp / f"size_{s.size_seconds:g}.rrd").stream():
        if chunk.is_static:
            static_entities.add(chunk.entity_path)
            continue
        batch = chunk.to_record_batch()
        rows[chunk.entity_path] = rows.get(chunk.entity_path, 0) + chunk.num_rows
        per = temporal.setdefault(chunk.entity_path, {})
        for name in batch.schema.names:
            per[name] = per.get(name, 0) + batch.column(name).nbytes
    per_sample_entities = sorted(e for e, n in rows.items() if n >= samples)
    other = sorted(e for e, n in rows.items() if n < samples)
    by_component: dict[str, float] = {}
    for e in per_sample_entities:
        for name, nbytes in temporal[e].items():
            key = name.split(":")[-1] if ":" in name else name
            by_component[key] = by_component.get(key, 0) + nbytes / samples  # /tf has several rows a sample
    r.section(f"6. Size: the default recording (one {s.size_seconds:g} s lap, {samples:,} samples)")
    r.add("file", f"{files[s.size_seconds]:,} B ({2 * s.size_seconds:g} s: {files[2 * s.size_seconds]:,} B)")
    r.add("bytes per sample (file growth per extra sample)", f"{per_sample:,.0f} B")
    r.add("static part (meshes, fixed transforms, axes, styles, blueprint)", f"{static_bytes:,.0f} B")
    r.add(f"entities written every sample ({len(per_sample_entities)})", ", ".join(per_sample_entities))
    r.add(
        "  uncompressed Arrow bytes per sample, by column",
        ", ".join(f"{k} {v:.0f}" for k, v in sorted(by_component.items(), key=lambda kv: -kv[1])),
    )
    r.add("entities with sparse temporal rows", ", ".join(other) or "none")
    r.figures["size"] = {
        "samples": samples,
        "file_bytes": files,
        "bytes_per_sample": per_sample,
        "static_bytes": static_bytes,
        "per_sample_entities": per_sample_entities,
        "sparse_temporal_entities": other,
        "static_entities": len(static_entities),
        "arrow_bytes_per_sample_by_column": by_component,
    }


# --- machine and output ----------------------------------------------------------------------------------


def machine() -> dict[str, Any]:
    cpu = "?"
    mem = "?"
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name"))
        kb = next(int(line.split()[1]) for line in open("/proc/meminfo") if line.startswith("MemTotal"))
        mem = f"{kb / 1024**2:.1f} GiB"
    except (OSError, StopIteration):
        pass
    versions = {}
    for pkg in ("r2d2-viz", "rerun-sdk", "yourdfpy", "trimesh", "numpy", "pyarrow"):
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = "-"
    return {
        "cpus": os.cpu_count(),
        "cpu_model": cpu,
        "ram": mem,
        "os": platform.platform(),
        "python": platform.python_version(),
        "packages": versions,
        "load_average_at_start": os.getloadavg(),
    }


def render(report: Report, info: dict[str, Any], mode: str, seconds: float) -> str:
    pk = ", ".join(f"{k} {v}" for k, v in info["packages"].items())
    lines = [
        f"Machine: {info['cpus']} CPUs ({info['cpu_model']}), {info['ram']} RAM, {info['os']}",
        f"Python {info['python']}; {pk}",
        f"Load average at start {info['load_average_at_start'][0]:.2f}, at end {info['load_average_at_end'][0]:.2f}; "
        f"{mode} run, {seconds:.0f} s",
        "",
        "| figure | value | goal | |",
        "|---|---|---|---|",
    ]
    lines += [f"| {a} | {b} | {c} | {d} |" for a, b, c, d in report.rows]
    lines += ["", *report.notes]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (CI): checks the script runs, no thresholds")
    parser.add_argument("--json", type=Path, default=None, metavar="PATH", help="also write the figures as JSON")
    parser.add_argument("--only", default=None, help="comma-separated sections: batch,kin,memory,live,robots,size")
    parser.add_argument("--rrlog-baseline", nargs=2, metavar=("SAMPLES", "OUT"), help=argparse.SUPPRESS)
    parser.add_argument("--sdk-floor", nargs=3, metavar=("RATE", "SECONDS", "OUT"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.sdk_floor:
        sdk_floor(float(args.sdk_floor[0]), float(args.sdk_floor[1]), Path(args.sdk_floor[2]))
        return 0
    if args.rrlog_baseline:
        rrlog_baseline(int(args.rrlog_baseline[0]), Path(args.rrlog_baseline[1]))
        return 0
    sizes = SMOKE if args.smoke else FULL
    only = set(args.only.split(",")) if args.only else {"batch", "kin", "memory", "live", "robots", "size"}
    info = machine()
    report = Report()
    report.notes += [
        "Ratios compare numbers measured side by side in this run (import floor and batch runs alternate); "
        "values are medians over the repeats; the machine may be shared, so absolute times vary between runs.",
        "The rr.log baseline logs the same entities and values one sample at a time (its kinematics precomputed, "
        "untimed) on a shorter run and is extrapolated per sample.",
        "Live figures come from the real app (--save X --realtime) with R2D2_VIZ_PACING_LOG: lateness is the time "
        "the sample's send returned minus its due time on the absolute schedule start + k / rate.",
    ]
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="r2d2-viz-bench-") as d:
        tmp = Path(d)
        batch_rss = float("nan")
        if "batch" in only:
            batch_rss = bench_batch(sizes, tmp, report)
        if "kin" in only:
            bench_kinematics(sizes, report)
        if "memory" in only:
            bench_memory(sizes, tmp, report, batch_rss)
        if "live" in only:
            bench_live(sizes, tmp, report)
        if "robots" in only:
            bench_robots(sizes, tmp, report)
        if "size" in only:
            bench_size(sizes, tmp, report)
    info["load_average_at_end"] = os.getloadavg()
    elapsed = time.perf_counter() - t0
    print(render(report, info, "smoke" if args.smoke else "full", elapsed))
    if args.json is not None:
        payload = {"mode": "smoke" if args.smoke else "full", "seconds": elapsed, "machine": info}
        payload |= report.figures
        args.json.write_text(json.dumps(payload, indent=2, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
