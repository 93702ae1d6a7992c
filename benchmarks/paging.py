#!/usr/bin/env python3
"""A recording bigger than the viewer's memory limit (issue 23, item 6): what the native viewer holds.

    python benchmarks/paging.py --rrd big.rrd                 # an existing recording
    python benchmarks/paging.py --data /work/bigdata          # r2d2-viz --save of bigbag.py's 100 s bag (~2 GB)

Opens the recording in the native viewer under Xvfb (``xvfb-run -a rerun FILE --memory-limit 500MB``, software
rendering), with and without the limit, and through Rerun's local catalog server (``rerun server -d DIR``, which
opens an .rrd by its footer; the viewer is pointed at the recording's URL — needs ``rerun.catalog``, i.e.
``pip install datafusion==54.0.0``), for ``--seconds`` each, and prints the viewer's peak RssAnon (its
processes but the X server, polled every 20 ms), its RssAnon at the end and every 10 s. Issue 23 expects Rerun 0.41
to page an .rrd that has its footer (chunk manifest) from disk under a memory limit: this checks what it holds.
One run each: a figure, not a test.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
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


def watch_viewer(command: list[str], seconds: float) -> tuple[float, float, list[float]]:
    """Peak RssAnon, RssAnon at the end and every 10 s (MB) of a viewer run under ``xvfb-run`` for ``seconds``."""
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    start, peak, now, trace = time.perf_counter(), 0.0, 0.0, []
    while proc.poll() is None and time.perf_counter() - start < seconds:
        now = viewer_anon_kb(proc.pid) / 1024
        peak = max(peak, now)
        if time.perf_counter() - start >= 10 * (len(trace) + 1):
            trace.append(now)
        time.sleep(bigbag.POLL_S)
    os.killpg(proc.pid, signal.SIGTERM)  # xvfb-run, its X server and the viewer
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    return peak, now, trace


@contextmanager
def catalog_server(rerun: str, rrd: Path, port: int) -> Iterator[str | None]:
    """``rerun server`` (Rerun's local catalog server, which reads an .rrd through its footer) serving ``rrd``;
    yields the recording's URL, or None when ``rerun.catalog`` is unavailable (it needs ``datafusion``)."""
    if importlib.util.find_spec("datafusion") is None:
        yield None
        return
    from rerun.catalog import CatalogClient

    with tempfile.TemporaryDirectory(dir=rrd.parent) as folder:
        (Path(folder) / rrd.name).hardlink_to(rrd)
        command = [rerun, "server", "--host", "127.0.0.1", "-p", str(port), "-d", f"big={folder}"]
        server = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            url = f"rerun+http://127.0.0.1:{port}"
            for _ in range(300):
                try:
                    dataset = CatalogClient(url).get_dataset(name="big")
                    break
                except Exception:  # not listening yet
                    time.sleep(0.1)
            else:
                raise SystemExit("rerun server did not start")
            yield str(dataset.segment_url(dataset.segment_ids()[0]))
        finally:
            os.killpg(server.pid, signal.SIGTERM)
            server.wait(timeout=30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rrd", type=Path, help="the recording (default: made from bigbag.py's 100 s bag)")
    parser.add_argument("--data", type=Path, default=Path("/tmp/r2d2-bigbag"), help="where the bags are kept")
    parser.add_argument("--seconds", type=float, default=90.0, help="how long the viewer stays open")
    parser.add_argument("--limit", default="500MB")
    parser.add_argument("--port", type=int, default=51299, help="the catalog server's port (loopback)")
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
    print("\n| viewer | peak RssAnon MB | at the end MB | every 10 s MB |\n|---|---:|---:|---|")
    xvfb_run = [xvfb, "-a", "-s", "-screen 0 1280x800x24", rerun]
    limit = ["--memory-limit", args.limit]
    runs = [(f"`rerun FILE --memory-limit {args.limit}`", [str(rrd), *limit]), ("`rerun FILE`", [str(rrd)])]
    for name, viewer_args in runs:
        peak, end, trace = watch_viewer([*xvfb_run, *viewer_args], args.seconds)
        print(f"| {name} | {peak:,.0f} | {end:,.0f} | {', '.join(f'{v:.0f}' for v in trace)} |")
    with catalog_server(rerun, rrd, args.port) as url:
        if url is None:
            print("\n(the catalog-server row needs rerun.catalog: pip install datafusion==54.0.0)")
            return
        peak, end, trace = watch_viewer([*xvfb_run, url, *limit], args.seconds)
        name = f"`rerun server -d DIR`, viewer on the recording's URL, `--memory-limit {args.limit}`"
        print(f"| {name} | {peak:,.0f} | {end:,.0f} | {', '.join(f'{v:.0f}' for v in trace)} |")


if __name__ == "__main__":
    main()
