"""Command line: ``r2d2-viz [--urdf PATH] [--motion …] [--duration S] [--rate HZ] [sink]``.

Exit codes: 0 done, 2 bad usage or bad input (one line on stderr, no traceback), 1 unexpected,
130 a batch run interrupted by Ctrl-C (its partial file removed), 141 stdout closed early (``| head``), quietly.
"""

from __future__ import annotations

import argparse
import gc
import math
import os
import sys
import traceback
from pathlib import Path

from r2d2_viz.cli.parser import (
    CONNECT_DEFAULT,
    EXIT_BAD_INPUT,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_UNEXPECTED,
    SAVE_SUFFIXES,
    build_parser,
    xacro_mappings,
)
from r2d2_viz.errors import DEBUG_ENV, ListenError, R2d2VizError, UsageError, shown, shown_in_line, stderr_line
from r2d2_viz.signals import sigterm_raises

EXIT_STDOUT_CLOSED = 141
"""stdout closed early (``r2d2-viz --bag b --list | head``): quiet, with the status a shell gives ``seq`` or ``cat``
killed by SIGPIPE (128 + 13), so ``set -o pipefail`` sees it as it sees theirs."""


_collector_paused = False


def main(argv: list[str] | None = None) -> int:
    global _collector_paused
    if gc.isenabled():  # until the imports are done: see _started
        gc.disable()
        _collector_paused = True
    from r2d2_viz.signals import stoppable

    stoppable()
    try:
        return _checked_main(argv)
    except BrokenPipeError:
        # the reader is gone: nothing more to say. Python would still flush stdout at exit and print "Exception
        # ignored … BrokenPipeError" (exit 120): stdout goes to /dev/null instead (Python's docs, "Note on SIGPIPE")
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return EXIT_STDOUT_CLOSED
    finally:
        _started()


def _started() -> None:
    """The imports done (rerun, numpy, pyarrow, the app: about a million objects, modules and classes that live as
    long as the process), Python's cyclic garbage collector runs again, with them frozen out of it. It walks every
    object it tracks at each full collection and once more at exit: during the imports and at exit that was ~0.2 s
    of CPU and ~0.25 s of wall beside a run of a few seconds (issue 38: the 1 h JointState bag)."""
    global _collector_paused
    if _collector_paused:
        _collector_paused = False
        gc.freeze()
        gc.enable()


def _checked_main(argv: list[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)  # --help prints here
    try:
        return _main(args, parser)
    except BrokenPipeError:
        raise
    except R2d2VizError as exc:
        print(stderr_line(f"error: {exc}{_which_flag(exc, args)}"), file=sys.stderr)
        if getattr(exc, "stuck", False):  # Rerun's file sink deadlocked (a full disk): its threads would hold the exit
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(EXIT_BAD_INPUT)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("r2d2-viz: interrupted; nothing saved", file=sys.stderr)
        return EXIT_INTERRUPTED
    except OSError as exc:
        if exc.filename is None or os.environ.get(DEBUG_ENV):  # not about a path: unexpected (the lines below)
            return _unexpected(exc)
        # a path the command line named (or one inside it) the system refused: too long, not allowed, no room…
        print(stderr_line(f"error: {shown_in_line(str(exc.filename))}: {exc.strerror or exc}"), file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as exc:
        return _unexpected(exc)


def _unexpected(exc: Exception) -> int:
    """A failure of ours: one line (the traceback with R2D2_VIZ_DEBUG=1), exit 1. Called in its ``except``."""
    if os.environ.get(DEBUG_ENV):
        traceback.print_exc()
    print(
        stderr_line(f"error: unexpected {type(exc).__name__}: {exc} (set R2D2_VIZ_DEBUG=1 for details)"),
        file=sys.stderr,
    )
    return EXIT_UNEXPECTED


def _which_flag(exc: R2d2VizError, args: argparse.Namespace) -> str:
    """The flag that sets a port that could not be listened on (the library's error knows the port, not the flag)."""
    if isinstance(exc, ListenError) and exc.port is not None and exc.port == getattr(args, "web_port", None):
        return "; choose another port with --web-port PORT"
    return ""


def _quiet_rerun() -> None:
    """Rerun's own log lines (Rust ``tracing``: ``WARN re_sdk::recording_stream: Recording disabled…``, with
    colour codes even into a file) off, unless ``R2D2_VIZ_DEBUG`` is set: its filter is read from ``RUST_LOG``
    once, when rerun is first imported (rerun 0.41), so it is set around that import only — the viewer and
    server processes started later get the environment as it was. Our own lines say what went wrong."""
    if os.environ.get(DEBUG_ENV) or "rerun" in sys.modules:
        return
    saved = os.environ.get("RUST_LOG")
    os.environ["RUST_LOG"] = "off"
    try:
        import r2d2_viz.viewer.sinks  # noqa: F401  (imports rerun)
    finally:
        if saved is None:
            del os.environ["RUST_LOG"]
        else:
            os.environ["RUST_LOG"] = saved


def _main(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    # Heavy imports (rerun, yourdfpy, trimesh) only after the arguments parsed: --help stays instant.
    from r2d2_viz.errors import SinkError, UsageError

    if args.save is not None and args.save.suffix not in SAVE_SUFFIXES and not args.save.is_dir():
        raise UsageError(
            f"--save {args.save}: unknown extension {args.save.suffix or '(none)'!r}; "
            "write a recording (.rrd) or a ROS 2 bag (.mcap)"
        )
    if args.bag is not None:  # "--bag b.mcap ur_type:=ur5e": the xacro arguments after the bags
        args.xacro_args = [*(str(b) for b in args.bag if ":=" in str(b)), *args.xacro_args]
        args.bag = [b for b in args.bag if ":=" not in str(b)] or None
    ends = [
        flag
        for flag, on in (
            ("--export-lerobot", args.export_lerobot),
            ("--render", args.render),
            ("--compare", args.compare),
        )
        if on is not None
    ]
    if len(ends) > 1:
        raise UsageError(f"choose one of {' and '.join(ends)} in one run")
    if args.export_lerobot is not None:  # bags -> a LeRobot dataset (issue 45)
        from r2d2_viz.run.export import export_main

        with sigterm_raises():  # a hangup or kill ends it as Ctrl-C does: nothing half-written
            return export_main(args)
    if args.render is not None:  # --render (issue 45): a view as a video, one per bag with --save-dir
        from r2d2_viz.cli.render import render_main

        with sigterm_raises():  # a hangup or kill ends it as Ctrl-C does: nothing half-written
            return render_main(args)
    if args.view is not None:
        raise UsageError("--view chooses the view --render draws: use it with --render OUT.mp4")
    if args.compare is not None:  # issue 47: several runs in one recording
        from r2d2_viz.cli.compare import compare_main

        with sigterm_raises():  # a hangup or kill ends it as Ctrl-C does: nothing half-written
            return compare_main(args)
    fleet = (args.save_dir, args.dataset, args.jobs, args.ray, args.summary)
    if args.force or any(value is not None for value in fleet):
        _quiet_rerun()
        from r2d2_viz.fleet.commands import fleet_main

        _started()

        return fleet_main(args)
    if args.bag is not None and len(args.bag) > 1:
        raise UsageError(f"{len(args.bag)} bags: give --save-dir DIR to convert them (one .rrd each)")
    args.bag = args.bag[0] if args.bag else None
    args.port = 9876 if args.port is None else args.port
    if args.connect is not None and ":=" in args.connect:  # "--connect ur_type:=ur5e": a xacro argument, not a URL
        args.xacro_args = [args.connect, *args.xacro_args]
        args.connect = CONNECT_DEFAULT
    live = [flag for flag, on in (("--spawn", args.spawn), ("--connect", args.connect), ("--serve", args.serve)) if on]
    if len(live) > 1:
        raise UsageError(f"choose one live sink, not {' and '.join(live)}")
    if args.headless and (live or args.save):
        raise UsageError("--headless shows nothing; it cannot be combined with a sink")
    if args.bag is not None and args.motion is not None:
        raise UsageError("--motion and --bag both say what moves the robot; choose one")
    if args.tf_tree is not None:
        from r2d2_viz.cli.system import tf_tree_main, tf_tree_sink

        if not (live or args.save or args.headless):
            _started()
            return tf_tree_main(args)
        tf_tree_sink(args)
    if args.list and not args.ros:
        if args.bag is None:
            raise UsageError("--list lists the topics of a live ROS 2 graph or a bag: use it with --ros or --bag PATH")
        _started()
        return _list_bag(args.bag)
    # rerun (0.7 s of CPU to import) only once a run needs it: a refused flag, --list and --tf-tree return first
    _quiet_rerun()
    from r2d2_viz.cli.run_args import run_config, sink_config
    from r2d2_viz.runner import print_summary, run
    from r2d2_viz.rviz.tools import parse_tool_topics

    _started()
    if args.ros:
        if args.bag is not None or args.motion not in (None, "sliders"):  # sliders: published on /joint_states
            raise UsageError("--ros shows the live graph; it cannot be combined with --bag or --motion (but sliders)")
        if args.list:
            return _list_topics()
    elif args.save is not None and args.save.suffix == ".mcap" and (live or args.realtime):
        raise UsageError(f"--save {args.save}: a bag is written as fast as it can, not with a live sink or --realtime")
    if not (math.isfinite(args.speed) and args.speed > 0):
        raise UsageError(f"--speed must be a positive factor, got {args.speed:g}")
    if args.topics is not None:  # "--topics /scan ur_type:=ur5e": the xacro argument is not a topic
        args.xacro_args += [t for t in args.topics if ":=" in t]
        args.topics = [t for t in args.topics if ":=" not in t] or None
    if args.bag is None and (args.start_offset or args.topics is not None):
        raise UsageError("--start-offset and --topics choose what of a bag to replay: use them with --bag")
    if args.plot and (args.bag is None or (args.save is not None and args.save.suffix == ".mcap")):
        raise UsageError("--plot plots a bag's fields in the viewer: use it with --bag (and not --save X.mcap)")
    if not (math.isfinite(args.start_offset) and args.start_offset >= 0):
        raise UsageError(f"--start-offset must be a number of seconds >= 0, got {args.start_offset:g}")
    _check_video(args)
    implied = not (live or args.save or args.headless)  # no sink flag: the native viewer (or the web one)
    sliders = args.motion == "sliders"  # joint_state_publisher_gui: on the page (served, or beside the native viewer)
    if sliders and (args.connect or args.headless or (args.save and not (args.serve or args.spawn))):
        raise UsageError("--motion sliders: the sliders are on a served page; use --serve or --spawn (with --save)")
    sink = sink_config(args, implied, page=sliders)
    fallback = sink.serve and not args.serve  # no window can open: the web viewer on loopback instead
    mappings = xacro_mappings(args)
    if args.tree:
        return _print_tree(args, mappings)
    config = run_config(
        args,
        mappings=mappings,
        sink=sink,
        realtime=args.realtime,
        ros=args.ros,
        tool_topics=parse_tool_topics(args.tool_topic),
        tf_tree=args.tf_tree is not None,
        watch=args.watch,
    )
    if args.watch and (args.bag is not None or args.ros or not config.live):
        why = "a bag's joints" if args.bag is not None else "--ros" if args.ros else "a batch --save (add --realtime)"
        if args.headless and args.bag is None and not args.ros:  # no --save was typed: advice about one is wrong
            why = "--headless, which shows nothing (use --serve, --spawn or --save FILE.rrd --realtime)"
        raise UsageError(f"--watch reloads a generated motion's robot in a live run, not with {why}")

    def on_ready(message: str) -> None:
        if fallback:
            message = _no_display(message, args.port, args.web_port)
        print(message, file=sys.stderr, flush=True)

    try:
        result = run(config, on_ready=on_ready)
    except SinkError as exc:
        if fallback:  # the user typed no --serve: say why it was tried
            why = f"no display for a viewer window, and the web viewer instead failed: {exc}"
            raise (ListenError(why, exc.port) if isinstance(exc, ListenError) else SinkError(why)) from None
        raise
    print_summary(result, config)
    return EXIT_OK


def _print_tree(args: argparse.Namespace, mappings: dict[str, str]) -> int:
    """``r2d2-viz --urdf X --tree``: check_urdf's tree on stdout; the description's warnings and impossible inertias
    on stderr, one line each."""
    from r2d2_viz.robot.inertial import inertia_problems
    from r2d2_viz.robot.model import default_urdf_path
    from r2d2_viz.robot.packages import PackageIndex
    from r2d2_viz.robot.tree_text import tree_lines
    from r2d2_viz.robot.xacro_load import load_robot

    if args.bag is not None or args.ros:
        raise UsageError("--tree prints the tree of a description file: use it with --urdf (or alone for the R2D2)")
    path = args.urdf or default_urdf_path()
    packages = PackageIndex.from_args(tuple(args.package_path), description=path, environ=os.environ)
    robot = load_robot(path, mappings=mappings, packages=packages)
    for line in (*robot.warnings, *inertia_problems(robot)):
        print(stderr_line(f"warning: {line}"), file=sys.stderr)
    print("\n".join(tree_lines(robot)), flush=True)
    return EXIT_OK


def _check_video(args: argparse.Namespace) -> None:
    """``--video`` goes with a bag or a live graph, into a recording, and needs PyAV (not imported here)."""
    from r2d2_viz.msgs.images import require_av

    if args.video is None:
        return
    if args.bag is None and not args.ros:
        raise UsageError("--video encodes the cameras of a bag or a live graph: use it with --bag or --ros")
    if args.save is not None and args.save.suffix == ".mcap":
        raise UsageError(f"--save {args.save}: a bag keeps its images as they are; --video is for recordings")
    require_av()


def _no_display(serving: str, port: int, web_port: int) -> str:
    """The one line of the fallback to the web viewer: why, the URL, and how to reach it from another machine."""
    forward = f"ssh -L {web_port}:localhost:{web_port} THIS-HOST"  # one port: the page carries the recording
    how = serving.removeprefix("serving: ")
    why = "no display for a viewer window: serving the web viewer instead"
    return f"{why}; {how} (on your own machine first: {forward})"


def _list_bag(path: Path) -> int:
    """``r2d2-viz --bag PATH --list``: every topic, however many (warnings show the first few), like ``ros2 bag
    info``, with its rate and bandwidth over the bag (``ros2 topic hz`` / ``bw``: one pass over its messages)."""
    from r2d2_viz.sources.bags.bag import open_bag
    from r2d2_viz.sources.system.topic_rates import rate_words, topic_rates

    with open_bag(path) as bag:
        rates = topic_rates(bag)
        for info in sorted(bag.topics.values(), key=lambda t: t.name):
            count = f"{info.count} message{'' if info.count == 1 else 's'}"
            print(shown(f"{info.name} [{info.msgtype}] {count}{rate_words(rates.get(info.name))}"), flush=True)
    return EXIT_OK


def _list_topics() -> int:
    """``r2d2-viz --ros --list``: like ``ros2 topic list -t``, with the publisher counts, then each node with what it
    publishes and subscribes (``ros2 node list`` + ``ros2 node info``); an empty graph says where
    it was searched and how to check (exit 0, like ``ros2 topic list``: an empty graph is an answer, not an error)."""
    from r2d2_viz.sources.live.dds import LIST_SECONDS, NODE_SECONDS, list_topics
    from r2d2_viz.sources.live.names import EMPTY_GRAPH_HINT, EMPTY_LIST_NEXT

    topics, nodes, discovery = list_topics()
    # a participant names its nodes (and DDS its topics) as it likes: a line break in one would print lines of
    # nodes and topics that do not exist, so each name stays on its line (shown_in_line)
    for topic, msgtype, publishers in topics:
        print(shown_in_line(f"{topic} [{msgtype}] {publishers} publisher{'' if publishers == 1 else 's'}"), flush=True)
    for node in nodes:  # then ros2 node list, each with ros2 node info's topics
        print(shown_in_line(f"node {node.name}"), flush=True)
        for verb, ends in (("publishes", node.publishes), ("subscribes", node.subscribes)):
            for topic, msgtype in ends:
                print(shown_in_line(f"  {verb} {topic} [{msgtype}]"), flush=True)
    if not topics:
        searched = f"no topics after {max(LIST_SECONDS, NODE_SECONDS):g} s of discovery on {discovery.searched()}"
        print(shown(f"r2d2-viz: {searched}"), file=sys.stderr)  # what was searched, then how to check: two short lines
        print(f"r2d2-viz: {EMPTY_GRAPH_HINT}; {EMPTY_LIST_NEXT}", file=sys.stderr, flush=True)
    return EXIT_OK
