"""``--tf-tree``: the TF tree of a bag (``--bag BAG --tf-tree [FILE]``) or of a live graph (``--ros --tf-tree``,
listening ``--duration`` seconds), printed, and written as a graph where FILE is given."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from r2d2_viz.cli.parser import EXIT_OK, xacro_mappings
from r2d2_viz.errors import BagError, UrdfError, UsageError, shown_in_line, stderr_line

if TYPE_CHECKING:
    from r2d2_viz.robot.model import Robot
    from r2d2_viz.robot.packages import PackageIndex
    from r2d2_viz.sources.bags.bag import Bag
    from r2d2_viz.sources.system.tf_read import TfSources
    from r2d2_viz.sources.system.tf_tree import TfTree

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
            tree = bag_tree(bag, _replayed(args, bag))
        title = f"TF tree of {args.bag}"
    else:
        tree, title = _motion_tree(args)
    if out is not None:
        write_whole(out, graph_data(tree, out, title))  # a hidden partial renamed over ``out`` when whole
    for line in tree_lines(tree, title):
        print(shown_in_line(line), flush=True)  # a frame name's escapes and line breaks shown, never sent
    if out is not None:
        print(shown_in_line(f"r2d2-viz: wrote {out}"), file=sys.stderr)
    return EXIT_OK


def _loader(args: argparse.Namespace) -> tuple[Callable[[], Robot], PackageIndex]:
    """``--urdf`` (or the R2D2) with its xacro arguments and packages, as a run loads it."""
    from r2d2_viz.robot.model import default_urdf_path
    from r2d2_viz.robot.packages import PackageIndex
    from r2d2_viz.robot.xacro_load import load_robot

    mappings = xacro_mappings(args)
    path = args.urdf or (None if args.bag is not None else default_urdf_path())
    packages = PackageIndex.from_args(tuple(args.package_path), description=path, environ=os.environ)
    return lambda: load_robot(args.urdf or default_urdf_path(), mappings=mappings, packages=packages), packages


def _replayed(args: argparse.Namespace, bag: Bag) -> TfSources | None:
    """What the replay of ``bag`` reads of TF and draws from robot descriptions (``--urdf``, or the bag's
    ``/robot_description``s): its plan. A description the replay could not use either is said in one line, and
    the tree is then the recorded TF's alone."""
    from r2d2_viz.sources.plan import plan_bag
    from r2d2_viz.sources.system.tf_read import tf_sources

    load, packages = _loader(args)
    try:
        plan = plan_bag(bag, load_robot=load if args.urdf is not None else None, packages=packages)
    except (BagError, UrdfError) as exc:
        if args.urdf is not None and isinstance(exc, UrdfError):
            raise
        print(stderr_line(f"warning: {exc}: the tree is the recorded TF's alone"), file=sys.stderr)
        return None
    return tf_sources(plan)


def _motion_tree(args: argparse.Namespace) -> tuple[TfTree, str]:
    """The tree of the robot (``--urdf``, or the tutorial's R2D2) under its generated motion (``--motion``), as
    robot_state_publisher and state_publisher.py publish it: over ``--duration`` (one lap: 48 s) at ``--rate``."""
    from r2d2_viz.kinematics.tree import compile_tree
    from r2d2_viz.runner import LAP_SAMPLES
    from r2d2_viz.sources.motion import default_motion, make_motion
    from r2d2_viz.sources.system.tf_robot import motion_tree

    if not (math.isfinite(args.rate) and args.rate > 0):
        raise UsageError(f"--rate must be a positive number of Hz, got {args.rate:g}")
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise UsageError(f"--duration must be a positive number of seconds, got {args.duration:g}")
    n = LAP_SAMPLES if args.duration is None else max(1, round(args.duration * args.rate))
    robot = _loader(args)[0]()
    source = make_motion(robot, args.motion, rate=args.rate, n_samples=n)
    tree = motion_tree(compile_tree(robot), source)
    name = args.urdf.name if args.urdf is not None else "the tutorial's R2D2"
    return tree, f"TF tree of {name} ({args.motion or default_motion(robot)} motion, {n} samples at {args.rate:g} Hz)"


def tf_tree_sink(args: argparse.Namespace) -> None:
    """``--tf-tree`` with a sink: the recording gets the TF graph view; a FILE belongs to the printed tree."""
    if args.tf_tree != "-":
        raise UsageError(
            f"--tf-tree {args.tf_tree}: the graph file goes with the printed tree; with a viewer or --save the "
            "recording holds the TF graph (give --tf-tree alone)"
        )
    if args.save is not None and args.save.suffix == ".mcap":
        raise UsageError(f"--save {args.save}: a bag has no graph view; --tf-tree goes with a recording (.rrd)")
