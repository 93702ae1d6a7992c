"""Time to the first frame of a mesh-heavy robot: r2d2-viz beside Rerun's own URDF loader (issue #10).

"First frame" is a whole command, process start to exit, both sides writing an .rrd:

* ours:  ``r2d2-viz --urdf X --save out.rrd --duration 0.04`` (the description, the meshes, one sample);
* Rerun: ``python -c "import rerun as rr; rr.init(...); rr.save(out); rr.log_file_from_path(X)"`` — Rerun's
  built-in URDF importer (Rust, in the SDK; the process waits for it to finish writing the file at exit),
  the same Python start-up and ``import rerun`` as ours;
* also printed: the ``rerun X --save out.rrd`` CLI (native, no Python) and the two import floors, which explain
  most of the difference;
* after imports: the same two in one process each, timed from after the imports (ours: ``r2d2_viz.cli``,
  ``runner``, ``sinks``, ``stream``, ``visuals`` and ``rerun``; Rerun: ``rerun``) to the end of
  ``cli.main([...])``, and to the return of ``flush()`` after ``log_file_from_path`` (which waits for the
  importer's data) — what the app does itself, without the start-up it shares with whatever else it imports.

Cold: our mesh cache (``$XDG_CACHE_HOME/r2d2-viz``, pointed at a temporary folder) is emptied before each cold
run; the OS page cache stays warm for both sides (it cannot be dropped here). Warm: the cache filled by a
previous run. Each round runs every command once, in turn, so a slow spell of the shared machine hits all of
them; figures are medians over rounds, and ratios are ratios of medians from this one run.

Both sides resolve ``package://example-robot-data/...`` through ``ROS_PACKAGE_PATH`` set to the installed
package's ``share`` folder (Rerun's importer needs it; ours also finds the package by walking up from the URDF).
The check after each model counts the mesh assets each side logged, so a side that silently dropped meshes
would show. Nothing is downloaded: example-robot-data is a pip package (the ``test`` extra).

    python benchmarks/first_frame.py [--rounds 5] [--models anymal-kinova,talos,g1]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

PY = sys.executable
MODELS = {
    "anymal-kinova": "robots/anymal_b_simple_description/robots/anymal-kinova.urdf",
    "talos": "robots/talos_data/robots/talos_reduced.urdf",
    "g1": "robots/g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
}
GOAL_COLD = 2.5
GOAL_WARM = 1.5
RERUN_SCRIPT = (
    "import sys, rerun as rr; rr.init('first_frame'); rr.save(sys.argv[2]); rr.log_file_from_path(sys.argv[1])"
)
RERUN_AFTER_IMPORTS = """
import sys, time
import rerun as rr
t = time.perf_counter()
rr.init("first_frame")
rr.save(sys.argv[2])
rr.log_file_from_path(sys.argv[1])
rr.get_global_data_recording().flush()
print(time.perf_counter() - t)
"""
OURS_AFTER_IMPORTS = """
import contextlib, io, sys, time
from r2d2_viz import cli, runner
from r2d2_viz.viewer import sinks, stream, visuals
import rerun
t = time.perf_counter()
with contextlib.redirect_stdout(io.StringIO()):
    code = cli.main(["--urdf", sys.argv[1], "--save", sys.argv[2], "--duration", "0.04"])
print(time.perf_counter() - t)
sys.exit(code)
"""


def share_dir() -> Path:
    """``share/`` of the installed example-robot-data (a cmeel wheel) — the folder that holds the package."""
    for root in {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}:
        share = Path(root) / "cmeel.prefix" / "share"
        if (share / "example-robot-data" / "package.xml").is_file():
            return share
    raise SystemExit("example-robot-data is not installed: pip install '.[test]'")


def timed(cmd: Sequence[str], env: dict[str, str]) -> float:
    start = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return seconds


def reported(cmd: Sequence[str], env: dict[str, str]) -> float:
    """Seconds the command prints on its last stdout line (its own in-process timing)."""
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return float(proc.stdout.split()[-1])


def count_assets(rrd: Path) -> int:
    """Mesh files drawn in a recording: entities with an Asset3D blob."""
    from rerun.chunk import RrdReader

    reader = RrdReader(rrd)
    entities: set[str] = set()
    for store in reader.recordings():
        for chunk in reader.stream(store=store):
            names = {f.name for f in chunk.to_record_batch().schema}
            if "Asset3D:blob" in names:
                entities.add(chunk.entity_path)
    return len(entities)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--models", default=",".join(MODELS))
    args = parser.parse_args(argv)
    share = share_dir()
    r2d2_viz = str(Path(PY).parent / "r2d2-viz")
    rerun_cli = str(Path(PY).parent / "rerun")
    with tempfile.TemporaryDirectory(prefix="first_frame-") as tmp_name:
        tmp = Path(tmp_name)
        cache = tmp / "xdg"
        env = {**os.environ, "ROS_PACKAGE_PATH": str(share), "XDG_CACHE_HOME": str(cache), "RUST_LOG": "warn"}
        floors = {
            "import floor, ours (python -c 'import r2d2_viz.cli, rerun')": [PY, "-c", "import r2d2_viz.cli, rerun"],
            "import floor, Rerun (python -c 'import rerun')": [PY, "-c", "import rerun"],
            # what ours would be without yourdfpy, which imports trimesh and scipy at start-up
            "import floor, ours without yourdfpy (python -c 'import rerun, numpy, pyarrow, lxml.etree')": [
                PY,
                "-c",
                "import rerun, numpy, pyarrow, lxml.etree",
            ],
        }
        rows: list[str] = []
        rows_in: list[str] = []
        floor_times: dict[str, list[float]] = {name: [] for name in floors}
        for name in args.models.split(","):
            urdf = share / "example-robot-data" / MODELS[name]
            ours = [r2d2_viz, "--urdf", str(urdf), "--save", str(tmp / "ours.rrd"), "--duration", "0.04"]
            rerun_py = [PY, "-c", RERUN_SCRIPT, str(urdf), str(tmp / "rerun.rrd")]
            rerun_native = [rerun_cli, str(urdf), "--save", str(tmp / "cli.rrd"), "--port", "0", "--bind", "127.0.0.1"]
            ours_in = [PY, "-c", OURS_AFTER_IMPORTS, str(urdf), str(tmp / "ours_in.rrd")]
            rerun_in = [PY, "-c", RERUN_AFTER_IMPORTS, str(urdf), str(tmp / "rerun_in.rrd")]
            times: dict[str, list[float]] = {
                k: [] for k in ("cold", "warm", "rerun", "cli", "in_cold", "in_warm", "in_rr")
            }
            for _ in range(args.rounds):
                shutil.rmtree(cache, ignore_errors=True)
                times["cold"].append(timed(ours, env))
                times["warm"].append(timed(ours, env))
                times["rerun"].append(timed(rerun_py, env))
                times["cli"].append(timed(rerun_native, env))
                shutil.rmtree(cache, ignore_errors=True)
                times["in_cold"].append(reported(ours_in, env))
                times["in_warm"].append(reported(ours_in, env))
                times["in_rr"].append(reported(rerun_in, env))
                for floor, cmd in floors.items():
                    floor_times[floor].append(timed(cmd, env))
            med = {k: statistics.median(v) for k, v in times.items()}
            cold, warm = med["cold"] / med["rerun"], med["warm"] / med["rerun"]
            shapes = f"{count_assets(tmp / 'ours.rrd')} / {count_assets(tmp / 'rerun.rrd')}"
            rows.append(
                f"| {name} | {med['cold']:.2f} s | {med['warm']:.2f} s | {med['rerun']:.2f} s | {med['cli']:.2f} s "
                f"| {cold:.2f}× {'✓' if cold <= GOAL_COLD else '✗'} | {warm:.2f}× {'✓' if warm <= GOAL_WARM else '✗'} "
                f"| {shapes} |"
            )
            in_cold, in_warm = med["in_cold"] / med["in_rr"], med["in_warm"] / med["in_rr"]
            rows_in.append(
                f"| {name} | {med['in_cold']:.2f} s | {med['in_warm']:.2f} s | {med['in_rr']:.2f} s "
                f"| {in_cold:.2f}× {'✓' if in_cold <= GOAL_COLD else '✗'} "
                f"| {in_warm:.2f}× {'✓' if in_warm <= GOAL_WARM else '✗'} |"
            )
        print(f"First frame, median of {args.rounds} rounds (whole commands; Python {sys.version.split()[0]})\n")
        print(
            "| model | ours cold | ours warm | Rerun loader (Python) | Rerun CLI | cold ratio "
            f"(goal ≤ {GOAL_COLD}×) | warm ratio (goal ≤ {GOAL_WARM}×) | mesh shapes ours / Rerun |"
        )
        print("|---|---|---|---|---|---|---|---|")
        print("\n".join(rows))
        print()
        for floor, values in floor_times.items():
            print(f"- {floor}: {statistics.median(values):.2f} s")
        print("\nAfter imports (in-process, same rounds)\n")
        print(
            f"| model | ours cold | ours warm | Rerun loader | cold ratio (goal ≤ {GOAL_COLD}×) "
            f"| warm ratio (goal ≤ {GOAL_WARM}×) |"
        )
        print("|---|---|---|---|---|---|")
        print("\n".join(rows_in))
    return 0


if __name__ == "__main__":
    sys.exit(main())
