#!/usr/bin/env python3
"""Issue 48, item 2: a bag run's start-up, its tail, and what an Arrow array built from numpy costs beside the reader.

    python benchmarks/startup.py --bag BAG.mcap     # phases of `r2d2-viz --bag BAG --save out.rrd`, medians of 3
    python benchmarks/startup.py --smoke            # the repository's small talker bag, once each (CI)

Three figures, each a median of ``--rounds``:

* **GIL handoffs**: a time column made by ``pa.array(numpy)`` (what ``viewer/columns.py`` did) and from its buffer
  (what it does), 2,000 calls each, alternating, beside a thread running Python (as the bag's reader thread does):
  wall and CPU per call of the calling thread. ``pa.array`` lets go of the GIL, and the caller then waits for the
  other thread to hand it back (up to ``sys.getswitchinterval()``, 5 ms).
* **phases** of a whole run in a subprocess (CPU of the process, ``resource.getrusage``, all threads): the imports
  (``import rerun`` alone, then the app's run modules), the run up to the end of the last window, the close (the
  last flush and the footer: ``close_recording``), and the exit after ``main`` returns (Rerun's ``atexit``, the
  interpreter's teardown) — its CPU from ``os.wait4``.
* the same phases' wall time (meaningful on a quiet machine only).

Outputs are deleted before every run. The script never fails on a figure.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pyarrow as pa

REPO = Path(__file__).resolve().parent.parent
SMOKE_BAG = REPO / "tests" / "data" / "bags" / "talker_mcap"
PHASES = """
import json, os, resource, sys, time
def cpu():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime
marks = [("start", time.perf_counter(), cpu())]
def mark(name):
    marks.append((name, time.perf_counter(), cpu()))
import rerun
mark("import rerun")
import r2d2_viz.runner as runner
from r2d2_viz.cli import main
mark("app imports")
close = runner.close_recording
def timed_close(recording):
    mark("windows")
    close(recording)
    mark("close (last flush, footer)")
runner.close_recording = timed_close
code = main(sys.argv[1:])
mark("main returned")
print("PHASES " + json.dumps(marks), file=sys.stderr)
sys.exit(code)
"""


def gil_handoffs(calls: int) -> dict[str, tuple[float, float]]:
    """Per call of the calling thread: (wall µs, CPU µs) for both ways, beside a busy Python thread."""
    times = np.arange(8, dtype=np.int64) + 1_700_000_000_000_000_000
    ways = {
        "pa.array(numpy)": lambda: pa.array(times.astype("datetime64[ns]")),
        "from buffers": lambda: pa.Array.from_buffers(
            pa.timestamp("ns"), len(times), [None, pa.py_buffer(times.copy())]
        ),
    }
    stop = threading.Event()

    def busy() -> None:
        x = 0
        while not stop.is_set():
            x += 1

    reader = threading.Thread(target=busy, daemon=True)
    reader.start()
    out: dict[str, tuple[float, float]] = {}
    try:
        for name, make in ways.items():
            wall, cpu = time.perf_counter(), time.thread_time()
            for _ in range(calls):
                make()
            out[name] = ((time.perf_counter() - wall) / calls * 1e6, (time.thread_time() - cpu) / calls * 1e6)
    finally:
        stop.set()
        reader.join()
    return out


def phases(bag: Path, scratch: Path) -> dict[str, tuple[float, float]]:
    """Each phase's (wall s, CPU s) of one whole run; the exit's CPU: the process's total (``os.wait4``) less what
    it had used when ``main`` returned."""
    out, log = scratch / "out.rrd", scratch / "stderr.txt"
    out.unlink(missing_ok=True)
    command = [sys.executable, "-c", PHASES, "--bag", str(bag), "--save", str(out)]
    with log.open("w") as stderr:
        started = time.perf_counter()
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=stderr, cwd=scratch)
        _, _, usage = os.wait4(process.pid, 0)
        ended = time.perf_counter() - started
    process.returncode = 0  # reaped by wait4
    line = next(x for x in log.read_text().splitlines() if x.startswith("PHASES "))
    marks = json.loads(line.removeprefix("PHASES "))
    result = {name: (w - marks[k][1], c - marks[k][2]) for k, (name, w, c) in enumerate(marks[1:])}
    result["exit (after main)"] = (ended - (marks[-1][1] - marks[0][1]), usage.ru_utime + usage.ru_stime - marks[-1][2])
    out.unlink(missing_ok=True)
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bag", type=Path, help="the bag (default: the repository's talker bag)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--smoke", action="store_true", help="the talker bag, once each, few calls (CI)")
    args = parser.parse_args()
    rounds, calls = (1, 200) if args.smoke else (args.rounds, 2000)
    bag = args.bag or SMOKE_BAG
    handoffs: dict[str, list[tuple[float, float]]] = {}
    runs: dict[str, list[tuple[float, float]]] = {}
    with tempfile.TemporaryDirectory() as scratch:
        for _ in range(rounds):  # the two figures alternate round by round
            for name, figure in gil_handoffs(calls).items():
                handoffs.setdefault(name, []).append(figure)
            for name, figure in phases(bag, Path(scratch)).items():
                runs.setdefault(name, []).append(figure)
    print(f"load: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; medians of {rounds}")
    print("time column beside a busy thread   wall µs/call   CPU µs/call")
    for name, figures in handoffs.items():
        wall, cpu = (statistics.median(f[i] for f in figures) for i in (0, 1))
        print(f"  {name:32s} {wall:12.1f} {cpu:12.1f}")
    print(f"r2d2-viz --bag {bag.name} --save out.rrd   wall s    CPU s (process, all threads)")
    for name, figures in runs.items():
        cpu = statistics.median(f[1] for f in figures)
        print(f"  {name:32s} {statistics.median(f[0] for f in figures):8.3f} {cpu:8.3f}")


if __name__ == "__main__":
    main()
