"""``r2d2-viz --compare A B [C…] [--align TOPIC] [--offset NAME=SECONDS] [--side-by-side] [--summary]``: the flags
checked (one line, exit 2, for what cannot go with a comparison), the runs compared (:mod:`r2d2_viz.run.compare`)
and the differences printed (``--summary``) or the recording made."""

from __future__ import annotations

import argparse
import sys

from r2d2_viz.cli.parser import EXIT_OK, SAVE_SUFFIXES, xacro_mappings
from r2d2_viz.errors import UsageError, shown

ALONE = (
    ("bag", "--bag"),
    ("ros", "--ros"),
    ("motion", "--motion"),
    ("list", "--list"),
    ("tree", "--tree"),
    ("save_dir", "--save-dir"),
    ("dataset", "--dataset"),
    ("ray", "--ray"),
    ("watch", "--watch"),
    ("tf_tree", "--tf-tree"),
)
"""Flags that say what to run, or how, otherwise: not with ``--compare``, whose runs are its own arguments."""


def compare_main(args: argparse.Namespace) -> int:
    from r2d2_viz.cli.run_args import sink_config
    from r2d2_viz.progress import wanted
    from r2d2_viz.run.compare import CompareConfig, compare
    from r2d2_viz.runner import RunConfig

    for name, flag in ALONE:
        if getattr(args, name, None) not in (None, False, []):
            raise UsageError(f"--compare takes its runs as its arguments; it cannot be combined with {flag}")
    if args.summary not in (None, "-"):
        raise UsageError(f"--compare … --summary prints the differences; it writes no file ({args.summary!r})")
    if args.save is not None and args.save.suffix not in SAVE_SUFFIXES[:1]:
        raise UsageError(f"--save {args.save}: a comparison is a recording: give a .rrd file")
    live = [flag for flag, on in (("--spawn", args.spawn), ("--connect", args.connect), ("--serve", args.serve)) if on]
    if len(live) > 1:
        raise UsageError(f"choose one live sink, not {' and '.join(live)}")
    implied = not (live or args.save or args.headless or args.summary)
    sink = sink_config(args, implied)
    base = RunConfig(
        urdf=args.urdf,
        mappings=xacro_mappings(args),
        package_paths=tuple(args.package_path),
        sink=sink,
        time=args.time,
        fixed_frame=args.fixed_frame,
        rviz=args.rviz,
        start_offset=args.start_offset,
        duration=args.duration,
        topics=tuple(args.topics) if args.topics is not None else None,
        plots=tuple(tuple(p) for p in args.plot),
        progress=wanted(),  # each run's replay shows its bar on a terminal
    )
    config = CompareConfig(
        tuple(args.compare),
        base,
        align=args.align,
        offsets=tuple(args.offset),
        side_by_side=args.side_by_side,
        summary_only=args.summary is not None,
    )
    result = compare(config, on_ready=lambda message: print(message, file=sys.stderr, flush=True))
    if config.summary_only:
        print("\n".join(result.summary), flush=True)
        return EXIT_OK
    where = f" to {result.saved}" if result.saved else ""
    print(shown(f"r2d2-viz: {len(result.names)} runs compared ({', '.join(result.names)}){where}"), file=sys.stderr)
    return EXIT_OK
