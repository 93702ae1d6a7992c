"""``--tf-tree``: the TF tree of a bag (``--bag BAG --tf-tree [FILE]``) or of a live graph (``--ros --tf-tree``,
listening ``--duration`` seconds), printed, and written as a graph where FILE is given."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from r2d2_viz.cli.parser import EXIT_OK
from r2d2_viz.errors import UsageError, shown_in_line

LISTEN_SECONDS = 5.0
"""How long ``--ros --tf-tree`` listens without ``--duration``."""


def tf_tree_main(args: argparse.Namespace) -> int:
    from r2d2_viz.sources.system.tf_report import GRAPH_SUFFIXES, graph_data, tree_lines
    from r2d2_viz.viewer.files.whole_file import check_target, write_whole

    out = None if args.tf_tree == "-" else Path(args.tf_tree)
    if out is not None and out.suffix not in GRAPH_SUFFIXES:
        raise UsageError(f"--tf-tree {out}: unknown extension {out.suffix or '(none)'!r}; write .dot or .svg")
    if out is not None:
        check_target(out)  # before the bag is read or the graph listened to
    if args.ros:
        if args.bag is not None:
            raise UsageError("--ros shows the live graph; it cannot be combined with --bag")
        seconds = LISTEN_SECONDS if args.duration is None else args.duration
        if not (math.isfinite(seconds) and seconds > 0):
            raise UsageError(f"--duration must be a positive number of seconds, got {seconds:g}")
        from r2d2_viz.sources.system.tf_live import live_tree

        tree, where = live_tree(seconds)
        title = f"TF tree of the ROS 2 graph on {where} ({seconds:g} s)"
    elif args.bag is not None:
        from r2d2_viz.sources.bags.bag import open_bag
        from r2d2_viz.sources.system.tf_read import bag_tree

        with open_bag(args.bag) as bag:
            tree = bag_tree(bag)
        title = f"TF tree of {args.bag}"
    else:
        raise UsageError("--tf-tree prints the TF tree of a bag or a live graph: use it with --bag PATH or --ros")
    if out is not None:
        write_whole(out, graph_data(tree, out, title))  # a hidden partial renamed over ``out`` when whole
    for line in tree_lines(tree, title):
        print(shown_in_line(line), flush=True)  # a frame name's escapes and line breaks shown, never sent
    if out is not None:
        print(shown_in_line(f"r2d2-viz: wrote {out}"), file=sys.stderr)
    return EXIT_OK


def tf_tree_sink(args: argparse.Namespace) -> None:
    """``--tf-tree`` with a sink: the recording gets the TF graph view; a FILE belongs to the printed tree."""
    if args.tf_tree != "-":
        raise UsageError(
            f"--tf-tree {args.tf_tree}: the graph file goes with the printed tree; with a viewer or --save the "
            "recording holds the TF graph (give --tf-tree alone)"
        )
    if args.bag is None and not args.ros:
        raise UsageError("--tf-tree shows the TF tree of a bag or a live graph: use it with --bag PATH or --ros")
    if args.save is not None and args.save.suffix == ".mcap":
        raise UsageError(f"--save {args.save}: a bag has no graph view; --tf-tree goes with a recording (.rrd)")
