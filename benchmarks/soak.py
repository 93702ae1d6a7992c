"""Soak: run r2d2-viz live at 1 kHz for 10 minutes and report how its memory grows (issue #5, goal < 10 %).

    python benchmarks/soak.py                  # 10 min at 1 kHz, live to a file (--save X --realtime)
    python benchmarks/soak.py --seconds 20     # a short run, e.g. in CI (no threshold there)

The app is the installed one (``python -m r2d2_viz``), in a subprocess; its resident memory (VmRSS from
/proc) is sampled every few seconds. Growth is measured from the sample at 1 minute (or at 25 % of a
short run), after start-up and the first buffers have settled, to the last sample. Exit status 0 in
every case: this reports, it does not judge.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def rss_mb(pid: int) -> float | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        return None
    return None


def soak(seconds: float, rate: float, interval: float) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "soak.rrd"
        command = [sys.executable, "-m", "r2d2_viz", "--save", str(out), "--realtime"]
        command += ["--rate", str(rate), "--duration", str(seconds)]
        proc = subprocess.Popen(command, stderr=subprocess.PIPE, text=True, cwd=tmp)
        samples: list[tuple[float, float]] = []
        start = time.monotonic()
        while proc.poll() is None:
            value = rss_mb(proc.pid)
            if value:  # None before /proc has it, 0 while the interpreter starts
                samples.append((time.monotonic() - start, value))
            time.sleep(interval)
        _, stderr = proc.communicate()
        if proc.returncode != 0:
            raise SystemExit(f"soak: r2d2-viz failed ({proc.returncode}): {stderr.strip()}")
        size = out.stat().st_size
    settle = min(60.0, 0.25 * seconds)
    settled = [v for t, v in samples if t >= settle]
    if len(settled) < 2:
        raise SystemExit("soak: too few memory samples; run longer")
    base, last = settled[0], settled[-1]
    return {
        "seconds": seconds,
        "rate_hz": rate,
        "samples": round(seconds * rate),
        "rss_settled_mb": base,
        "rss_end_mb": last,
        "rss_peak_mb": max(v for _, v in samples),
        "growth_percent": 100 * (last - base) / base,
        "file_mb": size / 1e6,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=600.0, help="length of the run (default 600)")
    parser.add_argument("--rate", type=float, default=1000.0, help="samples per second (default 1000)")
    parser.add_argument("--interval", type=float, default=2.0, help="seconds between memory samples")
    args = parser.parse_args(argv)
    r = soak(args.seconds, args.rate, args.interval)
    samples, rate, seconds = r["samples"], r["rate_hz"], r["seconds"]
    print(f"soak: {samples:,} samples live at {rate:g} Hz for {seconds:g} s, saved ({r['file_mb']:.0f} MB)")
    print(
        f"RSS: {r['rss_settled_mb']:.0f} MB once settled, {r['rss_end_mb']:.0f} MB at the end "
        f"(peak {r['rss_peak_mb']:.0f} MB)"
    )
    print(f"growth after settling: {r['growth_percent']:+.1f} % (goal < 10 %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
