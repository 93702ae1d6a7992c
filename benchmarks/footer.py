#!/usr/bin/env python3
"""What an .rrd footer costs a long live run (issue 23, item 6).

    python benchmarks/footer.py                          # 60 s at 1 kHz, footer on and off
    python benchmarks/footer.py --seconds 10 --rate 100  # quicker

Rerun writes a footer (the recording's chunk manifest, which lets the viewer page the file from disk) when its
``FileSink`` closes, and keeps the manifest's entries in memory until then: one per chunk written. A live run
(``--realtime``, or ``--save`` beside a live viewer) sends a chunk per frame, so the manifest grows with the run.
This runs ``r2d2-viz --save x.rrd --realtime --duration S --rate R`` twice, with ``rr.FileSink``'s
``write_footer`` forced on and off (a patch in the child, before the app starts), and prints each run's peak
RssAnon (process tree, polled every 20 ms), the file's size and whether ``rerun rrd verify`` accepts it.
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--rate", type=float, default=1000.0)
    args = parser.parse_args()
    rerun = bigbag._rerun()
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
