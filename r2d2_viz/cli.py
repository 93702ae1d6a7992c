"""Command line: ``r2d2-viz [--urdf PATH] [--motion …] [--duration S] [--rate HZ] [sink]``.

Exit codes: 0 done, 2 bad usage or bad input (one line on stderr, no traceback), 1 unexpected,
130 a batch run interrupted by Ctrl-C (its partial file removed).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import traceback
from pathlib import Path

from r2d2_viz.errors import DEBUG_ENV, R2d2VizError, UsageError, stderr_line
from r2d2_viz.sources.motion import MOTIONS

EXIT_OK, EXIT_UNEXPECTED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130
CONNECT_DEFAULT = "rerun+http://127.0.0.1:9876/proxy"
SAVE_SUFFIXES = (".rrd", ".mcap")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        """argparse's own errors: one line, exit 2 (argparse would print the whole usage)."""
        self.exit(EXIT_BAD_INPUT, f"error: {message} (see r2d2-viz --help)\n")


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="r2d2-viz",
        description="The ROS 2 'URDF with robot_state_publisher' tutorial robot, moving in the Rerun viewer.",
        epilog="Without a sink flag: the native viewer (--spawn), or on a machine without a display a web viewer on "
        "127.0.0.1 (--serve). Open a saved recording with: rerun out.rrd",
    )
    parser.add_argument(
        "--urdf", type=Path, default=None, help="robot description, URDF or xacro (default: the tutorial's R2D2)"
    )
    parser.add_argument("xacro_args", nargs="*", metavar="NAME:=VALUE", help="xacro arguments")
    parser.add_argument(
        "--package-path",
        action="append",
        default=[],
        metavar="DIR|NAME=DIR",
        help="where ROS packages are (repeatable): a package, a folder of packages, or NAME=DIR for one package",
    )
    parser.add_argument(
        "--motion",
        default=None,
        metavar="{" + ",".join(MOTIONS) + "}",
        help="tutorial: state_publisher.py; sweep: every joint back and forth; still: all zeros "
        "(default: tutorial if the robot has swivel, tilt and periscope, else sweep)",
    )
    parser.add_argument(
        "--duration",
        type=_number,
        default=None,
        metavar="SECONDS",
        help="robot time to generate (default: one lap, 1,440 samples, for --save; until Ctrl-C for live sinks); "
        "with --bag, the first SECONDS of the bag (from --start-offset)",
    )
    parser.add_argument("--rate", type=_number, default=30.0, metavar="HZ", help="samples per second (default 30)")
    bags = parser.add_argument_group(
        "replaying a bag (a rosbag2 directory, a .mcap or .db3 file, or a ROS 1 .bag file)"
    )
    bags.add_argument(
        "--bag",
        type=Path,
        nargs="+",
        default=None,
        metavar="PATH",
        help="replay this bag instead of a motion; several with --save-dir",
    )
    bags.add_argument(
        "--speed", type=_number, default=1.0, metavar="FACTOR", help="replay speed, like ros2 bag play --rate"
    )
    bags.add_argument(
        "--time",
        choices=("receive", "header"),
        default="receive",
        help="a bag's times: when messages were recorded (default) or their header stamps",
    )
    bags.add_argument(
        "--start-offset",
        type=_number,
        default=0.0,
        metavar="SECONDS",
        help="start this many seconds into the bag, like ros2 bag play --start-offset",
    )
    bags.add_argument(
        "--topics",
        nargs="+",
        default=None,
        metavar="TOPIC",
        help="replay only these topics of the bag, like ros2 bag play --topics (transforms: name /tf and "
        "/tf_static too; the robot's model is still read from /robot_description)",
    )
    bags.add_argument(
        "--plot",
        nargs="+",
        action="append",
        default=[],
        metavar="PATH",
        help="plot these fields in one view, Foxglove's message paths: /odom.twist.twist.linear.x, "
        "/joint_states.effort[2] (repeat the flag for more views)",
    )
    bags.add_argument(
        "--fixed-frame",
        default=None,
        metavar="FRAME",
        help="the 3D view's frame (default: the TF tree's root, or odom)",
    )
    bags.add_argument(
        "--shared-frames",
        default=None,
        metavar="FRAMES",
        help="several robots (every namespace with a robot_description): the frames they share, comma-separated, "
        "never prefixed with a robot's namespace (default: map,world,earth)",
    )
    fleet = parser.add_argument_group("fleets: many bags, one Rerun dataset")
    fleet.add_argument(
        "--save-dir", type=Path, default=None, metavar="DIR", help="convert every --bag to DIR/<bag name>.rrd"
    )
    fleet.add_argument("--jobs", type=int, default=None, metavar="N", help="bags converted at once (default: cores)")
    fleet.add_argument("--force", action="store_true", help="convert again the bags whose output is up to date")
    fleet.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="convert as Ray tasks: a running cluster (auto, HOST:PORT) or, without ADDRESS, a local Ray",
    )
    fleet.add_argument(
        "--dataset", type=Path, default=None, metavar="DIR", help="serve DIR's recordings as one dataset"
    )
    fleet.add_argument(
        "--summary",
        nargs="?",
        const="-",
        default=None,
        metavar="OUT",
        help="with --dataset: print one row per recording, or write it to OUT (.csv, .parquet)",
    )
    ros = parser.add_argument_group("joining a running ROS 2 graph (Cyclone DDS; ROS_DOMAIN_ID and friends apply)")
    ros.add_argument(
        "--ros",
        action="store_true",
        help="show the live graph: /robot_description (or --urdf), /joint_states, /tf, /tf_static and display "
        "topics; --duration is then seconds of wall time",
    )
    parser.add_argument(
        "--rviz", type=Path, default=None, metavar="CONFIG", help="lay the viewer out as this RViz config does"
    )
    parser.add_argument(
        "--list",
        action="store_true",
        help="print the topics and exit: with --bag every topic, type and message count (like ros2 bag info); "
        "with --ros the graph's topics, types and publishers (like ros2 topic list -t)",
    )
    parser.add_argument(
        "--video",
        nargs="?",
        const="av1",
        default=None,
        choices=("av1", "h264"),
        help="a bag's or live graph's 8-bit camera images as video (default av1; needs r2d2-viz[video])",
    )
    sinks = parser.add_argument_group("where the robot goes (--save combines with one live sink)")
    sinks.add_argument("--spawn", action="store_true", help="start the native Rerun viewer and stream live")
    sinks.add_argument(
        "--save", type=Path, default=None, metavar="PATH", help="write a recording (.rrd), or a ROS 2 bag (.mcap)"
    )
    sinks.add_argument(
        "--connect",
        nargs="?",
        const=CONNECT_DEFAULT,
        default=None,
        metavar="URL",
        help=f"stream live to a running viewer (default {CONNECT_DEFAULT})",
    )
    sinks.add_argument("--serve", action="store_true", help="serve a web viewer and stream live to it")
    sinks.add_argument("--headless", action="store_true", help="compute everything, show nothing (checks a URDF)")
    sinks.add_argument("--realtime", action="store_true", help="pace --save to the wall clock like a live run")
    sinks.add_argument("--bind", default="127.0.0.1", metavar="ADDR", help="address --serve listens on")
    sinks.add_argument(
        "--port", type=int, default=None, help="gRPC port for --spawn / --serve (default 9876; --dataset: 51234)"
    )
    sinks.add_argument("--web-port", type=int, default=9090, help="HTTP port of --serve's web viewer (default 9090)")
    sinks.add_argument(
        "--tool-topic",
        action="append",
        default=[],
        metavar="TOOL=TOPIC",
        help="--serve's toolbar: publish a tool (goal, pose_estimate, point, teleop) on TOPIC instead",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return _main(args, parser)
    except R2d2VizError as exc:
        print(stderr_line(f"error: {exc}"), file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("r2d2-viz: interrupted; nothing saved", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        if os.environ.get(DEBUG_ENV):
            traceback.print_exc()
        print(
            stderr_line(f"error: unexpected {type(exc).__name__}: {exc} (set R2D2_VIZ_DEBUG=1 for details)"),
            file=sys.stderr,
        )
        return EXIT_UNEXPECTED


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
    _quiet_rerun()
    from r2d2_viz.progress import wanted
    from r2d2_viz.runner import RunConfig, print_summary, run
    from r2d2_viz.rviz.tools import parse_tool_topics
    from r2d2_viz.viewer.sinks import SinkConfig, has_display

    if args.bag is not None:  # "--bag b.mcap ur_type:=ur5e": the xacro arguments after the bags
        args.xacro_args = [*(str(b) for b in args.bag if ":=" in str(b)), *args.xacro_args]
        args.bag = [b for b in args.bag if ":=" not in str(b)] or None
    fleet = (args.save_dir, args.dataset, args.jobs, args.ray, args.summary)
    if args.force or any(value is not None for value in fleet):
        from r2d2_viz.fleet.commands import fleet_main

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
    if args.list and not args.ros:
        if args.bag is None:
            raise UsageError("--list lists the topics of a live ROS 2 graph or a bag: use it with --ros or --bag PATH")
        return _list_bag(args.bag)
    if args.ros:
        if args.bag is not None or args.motion is not None:
            raise UsageError("--ros shows the live graph; it cannot be combined with --bag or --motion")
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
    implied = not (live or args.save or args.headless)  # no sink flag: the native viewer…
    fallback = implied and not has_display()  # …or, where no window can open, the web viewer on loopback
    sink = SinkConfig(
        spawn=args.spawn or (implied and not fallback),
        connect=args.connect,
        serve=args.serve or fallback,
        save=args.save,
        headless=args.headless,
        bind=args.bind,
        port=args.port,
        web_port=args.web_port,
    )
    mappings: dict[str, str] = {}
    for item in args.xacro_args:
        name, sep, value = item.partition(":=")
        if not sep or not name.isidentifier():
            raise UsageError(f"{item!r}: expected a xacro argument NAME:=VALUE")
        mappings[name] = value
    config = RunConfig(
        urdf=args.urdf,
        mappings=mappings,
        package_paths=tuple(args.package_path),
        motion=args.motion,
        rate=args.rate,
        duration=args.duration,
        sink=sink,
        realtime=args.realtime,
        bag=args.bag,
        speed=args.speed,
        time=args.time,
        fixed_frame=args.fixed_frame,
        shared_frames=_frames(args.shared_frames),
        rviz=args.rviz,
        ros=args.ros,
        start_offset=args.start_offset,
        topics=tuple(args.topics) if args.topics is not None else None,
        video=args.video,
        progress=wanted(),
        tool_topics=parse_tool_topics(args.tool_topic),
        plots=tuple(tuple(p) for p in args.plot),
    )

    def on_ready(message: str) -> None:
        if fallback:
            message = _no_display(message, args.port, args.web_port)
        print(message, file=sys.stderr, flush=True)

    try:
        result = run(config, on_ready=on_ready)
    except SinkError as exc:
        if fallback:  # the user typed no --serve: say why it was tried
            raise SinkError(f"no display for a viewer window, and the web viewer instead failed: {exc}") from None
        raise
    print_summary(result, config)
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


def _frames(text: str | None) -> tuple[str, ...] | None:
    """``--shared-frames map,world`` → its frames."""
    if text is None:
        return None
    from r2d2_viz.errors import UsageError

    frames = tuple(f.strip() for f in text.split(",") if f.strip())
    if not frames:
        raise UsageError(f"--shared-frames {text!r}: expected frame names separated by commas, such as map,world")
    return frames


def _no_display(serving: str, port: int, web_port: int) -> str:
    """The one line of the fallback to the web viewer: why, the URL, and how to reach it from another machine."""
    forward = f"ssh -L {web_port}:localhost:{web_port} -L {port}:localhost:{port} THIS-HOST"
    how = serving.removeprefix("serving: ")
    why = "no display for a viewer window: serving the web viewer instead"
    return f"{why}; {how} (on your own machine first: {forward})"


def _list_bag(path: Path) -> int:
    """``r2d2-viz --bag PATH --list``: every topic, however many (warnings show the first few), like ``ros2 bag
    info``."""
    from r2d2_viz.sources.bags.bag import open_bag

    with open_bag(path) as bag:
        for info in sorted(bag.topics.values(), key=lambda t: t.name):
            print(f"{info.name} [{info.msgtype}] {info.count} message{'' if info.count == 1 else 's'}", flush=True)
    return EXIT_OK


def _list_topics() -> int:
    """``r2d2-viz --ros --list``: like ``ros2 topic list -t``, with the publisher counts; an empty graph says where
    it was searched and how to check (exit 0, like ``ros2 topic list``: an empty graph is an answer, not an error)."""
    from r2d2_viz.sources.live.dds import LIST_SECONDS, list_topics
    from r2d2_viz.sources.live.names import EMPTY_GRAPH_HINT, EMPTY_LIST_NEXT

    topics, discovery = list_topics()
    for topic, msgtype, publishers in topics:
        print(f"{topic} [{msgtype}] {publishers} publisher{'' if publishers == 1 else 's'}", flush=True)
    if not topics:
        searched = f"no topics after {LIST_SECONDS:g} s of discovery on {discovery.searched()}"
        print(f"r2d2-viz: {searched}", file=sys.stderr)  # what was searched, then how to check: two short lines
        print(f"r2d2-viz: {EMPTY_GRAPH_HINT}; {EMPTY_LIST_NEXT}", file=sys.stderr, flush=True)
    return EXIT_OK
