"""The command line's flags: ``build_parser()`` (argparse, one error line and exit 2 on bad flags), its exit
codes and defaults. Imports nothing heavy: ``--help`` stays instant."""

from __future__ import annotations

import argparse
from pathlib import Path

from r2d2_viz.errors import UsageError
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
        help="tutorial: state_publisher.py; sweep: every joint back and forth; still: all zeros; sliders: a slider "
        "per joint in the served page, like joint_state_publisher_gui "
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
        help="with --dataset: print one row per recording, or write it to OUT (.csv, .parquet); with --compare: "
        "print what differs between the runs and exit",
    )
    # --compare (issue 47): several runs in one recording, aligned, the others' robots as ghosts
    runs = parser.add_argument_group("comparing runs: several bags (or .rrd recordings r2d2-viz wrote) on one timeline")
    runs.add_argument(
        "--compare",
        type=Path,
        nargs="+",
        default=None,
        metavar="RUN",
        help="one recording of these runs under /runs/<name>: aligned at their starts, the first robot as it is, the "
        "others as tinted ghosts, every --plot overlaid; with --summary, print what differs and exit",
    )
    runs.add_argument(
        "--align", default=None, metavar="TOPIC", help="--compare: align the runs at their first message on TOPIC"
    )
    runs.add_argument(
        "--offset",
        action="append",
        default=[],
        metavar="NAME=SECONDS",
        help="--compare: shift run NAME (its bag's name) this many seconds later on the timeline (repeatable)",
    )
    runs.add_argument(
        "--side-by-side", action="store_true", help="--compare: the runs' robots beside each other, not overlaid"
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
    bench = parser.add_argument_group("the URDF workbench (what RViz's RobotModel and check_urdf show)")
    bench.add_argument(
        "--tree", action="store_true", help="print the kinematic tree as check_urdf does (with each joint) and exit"
    )
    bench.add_argument(
        "--mass", action="store_true", help="each link's centre of mass: a red ball of lead of its mass (as RViz)"
    )
    bench.add_argument(
        "--inertia", action="store_true", help="each link's box of equal inertia on its principal axes (as RViz)"
    )
    bench.add_argument("--link-axes", action="store_true", help="each link's axes (RViz's RobotModel Show Axes)")
    bench.add_argument(
        "--watch",
        action="store_true",
        help="reload the robot when the description, a file xacro read or a mesh changes (live runs)",
    )
    parser.add_argument(
        "--list",
        action="store_true",
        help="print the topics and exit: with --bag every topic, type and message count (like ros2 bag info); "
        "with --ros the graph's topics, types and publishers (like ros2 topic list -t)",
    )
    parser.add_argument(
        "--tf-tree",
        nargs="?",
        const="-",
        default=None,
        metavar="FILE",
        help="print the TF tree and exit (like view_frames and tf2_monitor): each frame under its parent, static or "
        "its rate and largest gap, then the problems; with --bag the whole bag, with --ros --duration seconds "
        "(default 5); FILE.dot or FILE.svg also writes the graph. With a sink (--save, --spawn…): a TF tree graph "
        "view in the recording instead, each frame's rate and age at the time cursor",
    )
    parser.add_argument(
        "--video",
        nargs="?",
        const="av1",
        default=None,
        choices=("av1", "h264"),
        help="a bag's or live graph's 8-bit camera images as video (default av1; needs r2d2-viz[video])",
    )
    # --render (issue 45): a view of the run as a video, drawn by Rerun's renderer headless (r2d2_viz/run/render.py)
    video_out = parser.add_argument_group("a view as a video (--render; its frame rate is --fps, below)")
    video_out.add_argument(
        "--render",
        type=Path,
        default=None,
        metavar="OUT",
        help="render a view of the run, frame by frame, into OUT.mp4 (H.264) or OUT.gif; with --save-dir, "
        "OUT's extension (mp4 or gif) and one video per bag, DIR/<bag name>.mp4",
    )
    video_out.add_argument(
        "--view",
        default=None,
        metavar="NAME",
        help="--render this view of the layout, by its name or a part of it (default: the 3D view)",
    )
    video_out.add_argument(
        "--size", default="1280x720", metavar="WxH", help="--render's frame size in pixels (default 1280x720)"
    )
    # --export-lerobot (issue 45): bags -> a LeRobot v3.0 dataset, one episode per bag
    export = parser.add_argument_group("exporting bags as a LeRobot v3.0 dataset (one episode per bag)")
    export.add_argument(
        "--export-lerobot",
        type=Path,
        default=None,
        metavar="DIR",
        help="write every --bag as an episode of the LeRobot dataset DIR (appended; bags already in it skipped)",
    )
    export.add_argument(
        "--fps",
        type=_number,
        default=30.0,
        metavar="N",
        help="frames per second of --export-lerobot and --render (default 30)",
    )
    export.add_argument(
        "--action",
        default=None,
        metavar="TOPIC",
        help="the dataset's action: a command topic (JointState, JointTrajectory, Twist, Float64MultiArray)",
    )
    export.add_argument("--task", default=None, metavar="TEXT", help="the episodes' task, in words")
    export.add_argument(
        "--lerobot-codec",
        choices=("av1", "h264"),
        default="av1",
        help="the dataset's camera videos (default av1, as LeRobot's; needs r2d2-viz[video])",
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
    sinks.add_argument("--serve", action="store_true", help="serve a web viewer and stream live to it, until Ctrl-C")
    sinks.add_argument("--headless", action="store_true", help="compute everything, show nothing (checks a URDF)")
    sinks.add_argument("--realtime", action="store_true", help="pace --save to the wall clock like a live run")
    sinks.add_argument("--bind", default="127.0.0.1", metavar="ADDR", help="address --serve listens on")
    sinks.add_argument("--port", type=int, default=None, help="gRPC port for --spawn (default 9876; --dataset: 51234)")
    sinks.add_argument("--web-port", type=int, default=9090, help="HTTP port of --serve's web viewer (default 9090)")
    sinks.add_argument(
        "--tool-topic",
        action="append",
        default=[],
        metavar="TOOL=TOPIC",
        help="--serve's toolbar: publish a tool (goal, pose_estimate, point, teleop) on TOPIC instead",
    )
    return parser


def xacro_mappings(args: argparse.Namespace) -> dict[str, str]:
    """``--xacro-arg NAME:=VALUE`` … as xacro's mappings (a malformed one: :class:`UsageError`)."""
    mappings: dict[str, str] = {}
    for item in args.xacro_args:
        name, sep, value = item.partition(":=")
        if not sep or not name.isidentifier():
            raise UsageError(f"{item!r}: expected a xacro argument NAME:=VALUE")
        mappings[name] = value
    return mappings
