#!/usr/bin/env python3
"""What an .rrd footer costs a long live run (issue 23, item 6).

    python benchmarks/footer.py                          # 60 s at 1 kHz, footer on and off
    python benchmarks/footer.py --seconds 10 --rate 100  # quicker
    python benchmarks/footer.py --curve                  # 2 min at 1 kHz: the memory curve, per sample vs gathered

Rerun writes a footer (the recording's chunk manifest, which lets the viewer page the file from disk) when its
``FileSink`` closes, and keeps the manifest's entries in memory until then: one per chunk written. A live run
(``--realtime``, or ``--save`` beside a live viewer) sends a chunk per frame, so the manifest grows with the run.
This runs ``r2d2-viz --save x.rrd --realtime --duration S --rate R`` twice, with ``rr.FileSink``'s
``write_footer`` forced on and off (a patch in the child, before the app starts), and prints each run's peak
RssAnon (process tree, polled every 20 ms), the file's size and whether ``rerun rrd verify`` accepts it.

``--curve`` (issue 29): ``r2d2-viz --save x.rrd --realtime --rate 1000 --duration 120`` as the app runs it (a run
without a live viewer sends its transforms with the plot values, twice a second) beside the same run with the
transforms sent every sample (``RobotStream.gather`` forced off in the child), footer on in both: RssAnon of the
process tree every second, and the growth per minute after the first (a least-squares line over 60 s … the end).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bigbag

CHILD = """
import sys
import rerun as rr
_FileSink = rr.FileSink
footer = sys.argv.pop(1) == "on"
rr.FileSink = lambda path, write_footer=True, **kw: _FileSink(path, write_footer=footer, **kw)
from r2d2_viz.cli import main
sys.exit(main(sys.argv[1:]))
"""


PER_SAMPLE = """
import sys
import r2d2_viz.viewer.stream as stream
_init = stream.RobotStream.__init__
def init(self, *args, **kw):
    _init(self, *args, **kw)
    self.gather = False
stream.RobotStream.__init__ = init
from r2d2_viz.cli import main
sys.exit(main(sys.argv[1:]))
"""


def curve(seconds: float, rate: float, tmp: Path) -> None:
    """The live memory curve, as the app runs and with a chunk per sample (see the module docstring)."""
    import os
    import signal
    import time

    import numpy as np

    rerun = bigbag._rerun()
    print(f"r2d2-viz --save x.rrd --realtime --rate {rate:g} --duration {seconds:g}: RssAnon every second\n")
    print("| transforms sent | MB at 10 s | 60 s | peak | growth after 1 min | .rrd MB | `rerun rrd verify` |")
    print("|---|---:|---:|---:|---:|---:|---|")
    curves = {}
    for name, child in (("every sample", PER_SAMPLE), ("twice a second (the app)", None)):
        out = tmp / "curve.rrd"
        command = [bigbag.PY, "-c", child] if child else [bigbag.APP]
        command += ["--save", str(out), "--realtime", "--duration", f"{seconds:g}", "--rate", f"{rate:g}"]
        proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        start, samples = time.perf_counter(), []
        while proc.poll() is None:
            samples.append((time.perf_counter() - start, bigbag.rss_anon_kb(proc.pid) / 1024))
            time.sleep(1.0)
            if time.perf_counter() - start > seconds + 60:
                os.kill(proc.pid, signal.SIGINT)
        err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
        if proc.wait() != 0:
            raise RuntimeError(err[-2000:])
        t, mb = (np.array(v) for v in zip(*samples, strict=True))
        late = t >= 60
        slope = float(np.polyfit(t[late], mb[late], 1)[0]) * 60 if late.sum() > 2 else float("nan")
        at = {s: float(mb[np.searchsorted(t, s)]) if t[-1] >= s else float("nan") for s in (10, 60)}
        verify = "(no rerun binary)"
        if rerun is not None:
            check = subprocess.run([rerun, "rrd", "verify", str(out)], capture_output=True, text=True)
            verify = "passes" if check.returncode == 0 else "fails"
        size = out.stat().st_size / 1e6
        print(
            f"| {name} | {at[10]:,.0f} | {at[60]:,.0f} | {mb.max():,.0f} | {slope:+.1f} MB/min "
            f"| {size:,.0f} | {verify} |"
        )
        curves[name] = [round(float(m)) for m in mb]
    for name, mbs in curves.items():
        print(f"\n{name}, MB every second: {' '.join(map(str, mbs))}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--rate", type=float, default=1000.0)
    parser.add_argument("--curve", action="store_true", help="the 2-minute live memory curve (--seconds 120)")
    args = parser.parse_args()
    rerun = bigbag._rerun()
    if args.curve:
        with tempfile.TemporaryDirectory(prefix="r2d2-footer-") as tmp:
            curve(args.seconds if args.seconds != 60.0 else 120.0, args.rate, Path(tmp))
        return
    with tempfile.TemporaryDirectory(prefix="r2d2-footer-") as tmp:
        print(f"r2d2-viz --save x.rrd --realtime --duration {args.seconds:g} --rate {args.rate:g}\n")
        print("| footer | peak RssAnon MB | wall s | .rrd MB | `rerun rrd verify` |\n|---|---:|---:|---:|---|")
        for footer in ("off", "on"):
            out = Path(tmp) / f"{footer}.rrd"
            command = [bigbag.PY, "-c", CHILD, footer, "--save", str(out), "--realtime"]
            command += ["--duration", f"{args.seconds:g}", "--rate", f"{args.rate:g}"]
            run = bigbag.run_watched(command)
            if run.returncode != 0:
                raise RuntimeError(run.stderr[-2000:])
            verify = "(no rerun binary)"
            if rerun is not None:
                check = subprocess.run([rerun, "rrd", "verify", str(out)], capture_output=True, text=True)
                said = (check.stdout + check.stderr).strip().splitlines()
                verify = "passes" if check.returncode == 0 else "fails: " + said[0]
            size = out.stat().st_size / 1e6
            print(f"| {footer} | {run.peak_anon_mb:,.0f} | {run.wall:.1f} | {size:,.0f} | {verify} |")


if __name__ == "__main__":
    main()
