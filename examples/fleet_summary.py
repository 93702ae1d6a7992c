#!/usr/bin/env python3
"""A week of runs at a glance: the fleet summary of a folder of recordings, through Rerun's catalog.

    r2d2-viz --bag bags/* --save-dir fleet/          # one recording per bag, in parallel
    python examples/fleet_summary.py fleet/          # which runs went furthest, which joint moved fastest
    python examples/fleet_summary.py fleet/ --csv fleet.csv

``r2d2_viz.fleet_summary(DIR)`` starts a catalog server of its own on 127.0.0.1, queries it (DataFusion
dataframes) and returns a ``pyarrow.Table``: one row per recording (bag, duration_s, topics, distance_m,
max_joint_speed, fastest_joint, messages_<Type>, …). Needs ``pip install 'r2d2-viz[catalog]'``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pyarrow.csv as pacsv

import r2d2_viz


def main() -> None:
    parser = argparse.ArgumentParser(description="The fleet summary of a folder of r2d2-viz recordings.")
    parser.add_argument("folder", type=Path, help="recordings written by r2d2-viz --bag … --save-dir")
    parser.add_argument("--csv", type=Path, default=None, help="also write the whole table here")
    args = parser.parse_args()
    table = r2d2_viz.fleet_summary(args.folder)
    rows = sorted(table.to_pylist(), key=lambda r: -(r["distance_m"] or 0.0))
    total = sum(r["distance_m"] or 0.0 for r in rows)
    hours = sum(r["duration_s"] or 0.0 for r in rows) / 3600
    print(f"{len(rows)} runs, {hours:.2f} h, the robots' bases travelled {total:.1f} m in all")
    for r in rows:
        speed = f"{r['max_joint_speed']:.2f} ({r['fastest_joint']})" if r["max_joint_speed"] is not None else "-"
        distance = f"{r['distance_m']:.2f} m" if r["distance_m"] is not None else "no robot"
        print(f"  {r['bag']:<24} {r['duration_s'] or 0:8.1f} s  {distance:>10}  fastest joint {speed}")
    if args.csv is not None:
        pacsv.write_csv(table, args.csv)
        print(f"written: {args.csv}")


if __name__ == "__main__":
    main()
