#!/usr/bin/env python3
"""A recording bigger than the viewer's memory limit (issue 23, item 6): what the native viewer holds.

    python benchmarks/paging.py --rrd big.rrd                 # an existing recording
    python benchmarks/paging.py --data /work/bigdata          # r2d2-viz --save of bigbag.py's 100 s bag (~2 GB)

Opens the recording in the native viewer under Xvfb (``xvfb-run -a rerun FILE --memory-limit 500MB``, software
rendering), with and without the limit, for ``--seconds`` each, and prints the viewer's peak RssAnon (its
processes but the X server, polled every 20 ms) and its RssAnon at the end. Rerun 0.41 pages an .rrd that has its
footer (chunk manifest) from disk; without the footer it must load the file to know what is in it.
One run each: a figure, not a test.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bigbag


def viewer_anon_kb(pid: int) -> int:
    """RssAnon of the processes under ``pid`` but the X server (its framebuffer is not the viewer's)."""
    total = 0
    for p in bigbag._tree(pid):
        try:
            if Path(f"/proc/{p}/comm").read_text().strip() == "Xvfb":
                continue
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("RssAnon:"):
                    total += int(line.split()[1])
        except OSError:
            continue
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rrd", type=Path, help="the recording (default: made from bigbag.py's 100 s bag)")
    parser.add_argument("--data", type=Path, default=Path("/tmp/r2d2-bigbag"), help="where the bags are kept")
    parser.add_argument("--seconds", type=float, default=60.0, help="how long the viewer stays open")
    parser.add_argument("--limit", default="500MB")
    args = parser.parse_args()
    rerun, xvfb = bigbag._rerun(), shutil.which("xvfb-run")
    if rerun is None or xvfb is None:
        raise SystemExit("needs the rerun binary and xvfb-run")
    rrd = args.rrd
    if rrd is None:
        rrd = args.data / "sensors_100s.rrd"
        if not rrd.exists():
            bag = bigbag.sensor_bag(args.data, 100.0)
            subprocess.run([bigbag.APP, "--bag", str(bag), "--save", str(rrd)], check=True)
    verify = subprocess.run([rerun, "rrd", "verify", str(rrd)], capture_output=True, text=True)
    verdict = "passes" if verify.returncode == 0 else "fails"
    print(f"{rrd}: {rrd.stat().st_size / 1e9:.2f} GB, rerun rrd verify: {verdict}")
    print("\n| viewer | peak RssAnon MB | RssAnon at the end MB |\n|---|---:|---:|")
    for limit in (["--memory-limit", args.limit], []):
        command = [xvfb, "-a", "-s", "-screen 0 1280x800x24", rerun, str(rrd), *limit]
        last: list[float] = []
        start = time.perf_counter()
        proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        peak = 0.0
        while proc.poll() is None and time.perf_counter() - start < args.seconds:
            now = viewer_anon_kb(proc.pid) / 1024
            peak, last = max(peak, now), [now]
            time.sleep(bigbag.POLL_S)
        os.killpg(proc.pid, signal.SIGTERM)  # xvfb-run, its X server and the viewer
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        name = f"`rerun FILE {' '.join(limit)}`".replace(" `", "`")
        print(f"| {name} | {peak:,.0f} | {last[0] if last else 0:,.0f} |")


if __name__ == "__main__":
    main()
