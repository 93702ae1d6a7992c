#!/usr/bin/env python3
"""Bags of several storage files (issue 33): what reading them as one time-ordered stream costs.

    python benchmarks/split_bags.py --data /work/bigdata   # the 30 s sensor bag of bigbag.py (~600 MB), reused
    python benchmarks/split_bags.py --seconds 3            # a 3 s one, written in a temporary folder

One full pass of ``Bag.blocks`` over every topic, in one process, alternating, medians of ``--rounds``:

* **one file** (the sensor MCAP of ``benchmarks/bigbag.py``), against the same pass by the previous ``Bag`` (the
  ``main`` branch's ``bag.py`` given with ``--old``, optional): what a single-file bag pays for the multi-file path;
* **two files that overlap completely** (the same MCAP hard-linked twice into a folder without metadata.yaml:
  every block merged, the worst case) against **one file read twice in turn** (what two files that do not
  overlap cost: they are read one after the other, block for block, as one file is). Overlapping files pay the
  merge: their messages' bytes copied once.

Each pass is checked to come out in time order with every message. The machine may be shared: say the load.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bigbag import sensor_bag

from r2d2_viz.sources.bags import bag as new_bag


def full_pass(open_bag: Callable[..., object], path: Path) -> tuple[float, int]:
    """Seconds and messages of one pass over every topic; asserts the time order."""
    start = time.perf_counter()
    n, last = 0, -1
    with open_bag(path, warn=lambda _: None) as bag:  # type: ignore[attr-defined]
        for block in bag.blocks(list(bag.topics)):
            times = block.times_ns
            assert int(times[0]) >= last and bool((times[1:] >= times[:-1]).all()), "out of time order"
            n, last = n + len(block), int(times[-1])
    return time.perf_counter() - start, n


def _module(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location("old_bag", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, help="where bigbag.py keeps its bags (reused when present)")
    parser.add_argument("--seconds", type=float, default=30.0, help="length of the sensor bag (30 s: ~600 MB)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--old", type=Path, help="the previous bag.py (git show main:r2d2_viz/sources/bags/bag.py)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="r2d2-split-") as scratch:
        mcap = sensor_bag(args.data or Path(scratch), args.seconds)
        overlapping = Path(scratch) / "overlapping"
        overlapping.mkdir()
        for name in ("a.mcap", "b.mcap"):
            os.link(mcap, overlapping / name)
        disjoint = mcap.parent  # one file; "two disjoint files" = the single file's pass twice, in turn
        runs: dict[str, Callable[[], tuple[float, int]]] = {
            "one file": lambda: full_pass(new_bag.open_bag, mcap),
            "one file read twice": lambda: _twice(lambda: full_pass(new_bag.open_bag, disjoint)),
            "two overlapping files (merged)": lambda: full_pass(new_bag.open_bag, overlapping),
        }
        if args.old:
            old = _module(args.old)
            runs["one file, previous Bag"] = lambda: full_pass(old.open_bag, mcap)
        times: dict[str, list[float]] = {k: [] for k in runs}
        counts: dict[str, int] = {}
        for _ in range(args.rounds):
            for name, run in runs.items():
                seconds, counts[name] = run()
                times[name].append(seconds)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"sensor bag {mcap.stat().st_size / 1e6:,.0f} MB, medians of {args.rounds}, load {os.getloadavg()[0]:.1f}")
    for name, m in med.items():
        print(f"| {name} | {m:.3f} s | {counts[name]:,} messages |")
    if "one file, previous Bag" in med:
        print(f"| one file: this Bag / previous Bag | {med['one file'] / med['one file, previous Bag']:.2f}× |")
    merged = med["two overlapping files (merged)"] / med["one file read twice"]
    print(f"| merged / read twice in turn | {merged:.2f}× |")


def _twice(run: Callable[[], tuple[float, int]]) -> tuple[float, int]:
    a, n = run()
    b, m = run()
    return a + b, n + m


if __name__ == "__main__":
    main()
