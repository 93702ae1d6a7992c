"""``--export-lerobot`` (issue 45) beside a plain ``--save`` of the same bag, side by side in one run.

The bag (tests/lerobotbags.py, written by rosbags): a two-joint arm's ``/joint_states`` at 50 Hz, a JointTrajectory
command at 10 Hz and a 320x240 rgb8 camera at 10 Hz, 60 s (``--smoke``: 3 s). Each round runs, alternating so the
machine's load falls on both alike, outputs deleted first:

* ``r2d2-viz --bag B --save out.rrd`` (the viewer's recording of the whole bag, lossless images);
* ``r2d2-viz --bag B --export-lerobot DIR --action … `` (30 fps frames, AV1 video as LeRobot's defaults).

Medians of 3 rounds (``--smoke``: 1, no verdicts); wall seconds of the whole CLI process, and their ratio.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from lerobotbags import write_arm_bag  # noqa: E402

CLI = [sys.executable, "-c", "from r2d2_viz.cli import main; raise SystemExit(main())"]


def timed(args: list[str], out: Path) -> float:
    """Wall seconds of one CLI run (its output deleted first)."""
    if out.is_dir():
        shutil.rmtree(out)
    out.unlink(missing_ok=True)
    start = time.perf_counter()
    done = subprocess.run([*CLI, *args], capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(args)}: exit {done.returncode}: {done.stderr.strip()[-500:]}")
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="a 3 s bag, one round (CI)")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    seconds, rounds = (3.0, 1) if args.smoke else (60.0, args.rounds)
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        bag = write_arm_bag(tmp / "arm", seconds=seconds).path
        rrd, dataset = tmp / "out.rrd", tmp / "dataset"
        runs: dict[str, list[float]] = {"save": [], "export": []}
        for _ in range(rounds):
            runs["save"].append(timed(["--bag", str(bag), "--save", str(rrd)], rrd))
            export = [
                "--bag",
                str(bag),
                "--export-lerobot",
                str(dataset),
                "--action",
                "/arm_controller/joint_trajectory",
            ]
            runs["export"].append(timed(export, dataset))
    save, export = (statistics.median(runs[k]) for k in ("save", "export"))
    print(f"| {seconds:g} s bag, median of {rounds} | wall |")
    print("|---|---|")
    print(f"| `--save out.rrd` | {save:.2f} s |")
    print(f"| `--export-lerobot DIR --action …` (30 fps, AV1) | {export:.2f} s |")
    print(f"| ratio export / save | {export / save:.2f}x |")


if __name__ == "__main__":
    main()
