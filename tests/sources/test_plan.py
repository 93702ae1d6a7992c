"""A bag's run plan (sources/plan.plan_bag: what is read before the first frame, bounded; --start-offset,
--topics) and bags replayed through the command line: bags written by rosbags (tests/bagmaker.py), read back from
the recording with Rerun's reader; poses against yourdfpy's forward kinematics of the bag's joint states."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from bagmaker import T0, TYPES, BagSpec, joint_state, string, tf_message, write_bag
from conftest import REPO, cli
from displaybags import occupancy_grid
from rrd import frame_edges_at, pose_in, read_recording, tf_by_child

from r2d2_viz.errors import BagError
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.plan import LOOKAHEAD_NS, PREROLL_NS, TF_SAMPLE_NS, BagChoice, plan_bag
from r2d2_viz.sources.playback import Segment

ARM = REPO / "examples" / "arm6.urdf"
ARM_JOINTS = ("base_yaw", "shoulder_pitch", "elbow", "wrist_pitch", "wrist_roll")
MS = 1_000_000
YAW_90 = (0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5))


def _arm_bag(path: Path, *, storage: str, n: int = 50, description: bool = True, bad_tf: bool = False) -> dict:
    """The arm: five joints at 50 Hz and the tool slide at 10 Hz (two publishers, subsets of the joints), the base
    driving along x in odom (/tf), a camera fixed on the base (/tf_static, not in the URDF)."""
    spec = BagSpec()
    if description:
        spec.add("/robot_description", T0, string(ARM.read_text()))
    spec.add("/tf_static", T0, tf_message([(T0, "base_link", "camera", (0.1, 0, 0.3), YAW_90)]))
    rng = np.random.default_rng(1)
    states = []
    for k in range(n):
        t = T0 + (k + 1) * 20 * MS
        q = rng.uniform(-1, 1, len(ARM_JOINTS))
        spec.add("/joint_states", t, joint_state(t, ARM_JOINTS, q))
        states.append((t, dict(zip(ARM_JOINTS, q, strict=True))))
        if k % 5 == 0:
            spec.add("/joint_states", t + MS, joint_state(t + MS, ["tool_slide"], [0.01 * (k % 4)]))
            states.append((t + MS, {"tool_slide": 0.01 * (k % 4)}))
        items = [(t, "odom", "base_link", (0.01 * k, 0, 0), (0, 0, 0, 1))]
        if bad_tf:  # robot_state_publisher would say shoulder is 0.1 m above base_link; 5 cm off
            items.append((t, "base_link", "shoulder", (0, 0, 0.15), (0, 0, 0, 1)))
        spec.add("/tf", t, tf_message(items))
    write_bag(path, spec, storage=storage)
    return {"states": states}


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bag_moves_the_robot_by_its_joint_states(tmp_path: Path, storage: str) -> None:
    bag = tmp_path / "arm_bag"
    made = _arm_bag(bag, storage=storage)
    out = tmp_path / "arm.rrd"
    result = cli("--bag", str(bag), "--save", str(out))
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    urdf = yourdfpy.URDF.load(str(ARM), load_meshes=False)
    held = dict.fromkeys((*ARM_JOINTS, "tool_slide"), 0.0)
    worst = 0.0
    for t, values in made["states"]:
        held.update(values)  # the others keep their last value, like robot_state_publisher
        urdf.update_cfg(held)
        edges = frame_edges_at(recording, t)
        k = (t - T0) // (20 * MS) - 1  # the latest /tf: x = 0.01 k, sent at T0 + (k + 1) · 20 ms
        T_odom_base = np.eye(4)
        T_odom_base[0, 3] = 0.01 * k
        for link in ("shoulder", "forearm", "tool"):
            expected = T_odom_base @ urdf.get_transform(frame_to=link, frame_from="base_link")
            worst = max(worst, float(np.abs(pose_in(edges, link, "odom") - expected).max()))
    assert worst < 1e-5
    # the camera, known only to the bag, hangs where /tf_static put it; the timeline holds the receive times
    camera = pose_in(frame_edges_at(recording, T0 + 20 * MS), "camera", "base_link")
    assert np.allclose(camera[:3, 3], [0.1, 0, 0.3], atol=1e-6)
    assert tf_by_child(recording)["shoulder"].times[0] == T0 + 20 * MS
    assert "/tf_axes/camera" in recording and "/robot/visual/forearm/0" in recording


def test_a_tf_only_bag_replays_its_frames(tmp_path: Path) -> None:
    bag = tmp_path / "tf_only"
    _arm_bag(bag, storage="mcap", description=False)
    spec_only_tf = tmp_path / "tf_only_no_states"
    spec = BagSpec()
    for k in range(30):
        t = T0 + k * 10 * MS
        spec.add("/tf", t, tf_message([(t, "map", "odom", (k * 0.1, 0, 0), (0, 0, 0, 1))]))
    write_bag(spec_only_tf, spec)
    out = tmp_path / "tf.rrd"
    result = cli("--bag", str(spec_only_tf), "--save", str(out))
    assert result.returncode == 0, result.stderr
    assert "TF-only replay" in result.stderr
    recording = read_recording(out)
    assert len(tf_by_child(recording)["odom"].times) == 30
    assert np.allclose(pose_in(frame_edges_at(recording, T0 + 290 * MS), "odom", "map")[:3, 3], [2.9, 0, 0])
    assert "/tf_axes/map" in recording and "/robot" not in {p.split("/")[1] for p in recording if p.count("/")}


def test_recorded_tf_that_disagrees_with_the_kinematics_is_reported_once(tmp_path: Path) -> None:
    bag = tmp_path / "bad_tf"
    _arm_bag(bag, storage="mcap", bad_tf=True)
    result = cli("--bag", str(bag), "--save", str(tmp_path / "x.rrd"))
    assert result.returncode == 0, result.stderr
    assert result.stderr.count("disagrees with the kinematics") == 1
    assert "50 mm" in result.stderr


@pytest.mark.parametrize(
    ("make", "problem"),
    [
        (lambda p: p.mkdir(), "metadata.yaml"),
        (lambda p: (p.mkdir(), (p / "bag_0.db3").write_bytes(b"junk" * 1024)), "cannot read this bag"),
        (lambda p: p.with_suffix(".mcap").write_bytes(b"not a bag at all"), ""),
        (lambda p: None, "no such file or directory"),
    ],
)
def test_bad_bags_are_one_line_and_exit_2(tmp_path: Path, make, problem: str) -> None:
    target = tmp_path / "bag"
    make(target)
    path = target.with_suffix(".mcap") if target.with_suffix(".mcap").exists() else target
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(path), "--save", str(out))
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in result.stderr
    assert problem in lines[0] and not out.exists() and not list(tmp_path.glob(".out.rrd*"))


def test_a_wrong_type_on_joint_states_is_refused(tmp_path: Path) -> None:
    spec = BagSpec(types={"/joint_states": "std_msgs/msg/String"})
    spec.add("/joint_states", T0, string("hello"))
    write_bag(tmp_path / "wrong", spec)
    result = cli("--bag", str(tmp_path / "wrong"), "--urdf", str(ARM), "--save", str(tmp_path / "o.rrd"))
    assert result.returncode == 2 and "/joint_states" in result.stderr and "Traceback" not in result.stderr


def test_live_replay_is_paced_at_the_speed_asked(tmp_path: Path) -> None:
    bag = tmp_path / "arm_bag"
    _arm_bag(bag, storage="mcap", n=100)  # 2 s of joint states
    out = tmp_path / "live.rrd"
    exe = Path(sys.executable).parent / "r2d2-viz"
    start = time.monotonic()
    result = subprocess.run(
        [str(exe), "--bag", str(bag), "--save", str(out), "--realtime", "--speed", "4"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    elapsed = time.monotonic() - start
    assert result.returncode == 0, result.stderr
    assert elapsed >= 2.0 / 4 * 0.95  # the last joint state is due 1.98 s / 4 after the first
    recording = read_recording(out)
    assert len(tf_by_child(recording)["shoulder"].times) == 120  # 100 arm messages, 20 tool slide messages


S = 1_000_000_000
MAP = "nav_msgs/msg/OccupancyGrid"


def _long_bag(path: Path) -> Path:
    """10 s of the arm: joint states and /tf every 20 ms, a camera on /tf_static, maps at 1, 3 and 7 s (x = k/10 m
    along odom at T0 + k · 100 ms), and the robot's description recorded last."""
    spec = BagSpec(types={**TYPES, "/map": MAP})
    spec.add("/tf_static", T0, tf_message([(T0, "base_link", "camera", (0.1, 0, 0.3), YAW_90)]))
    for k in range(500):
        t = T0 + k * 20 * MS
        spec.add("/joint_states", t, joint_state(t, ARM_JOINTS, [k / 500] * 5))
        spec.add("/tf", t + 1, tf_message([(t, "odom", "base_link", (k / 50, 0, 0), (0, 0, 0, 1))]))
    for second in (1, 3, 7):
        spec.add("/map", T0 + second * S + 5, occupancy_grid())
    spec.add("/robot_description", T0 + 10 * S, string(ARM.read_text()))
    return write_bag(path, spec)


def test_the_plan_reads_a_bounded_look_ahead_and_finds_a_description_recorded_last(tmp_path: Path) -> None:
    path = _long_bag(tmp_path / "long")
    reads: list[tuple[tuple[str, ...], int | None, int | None, int]] = []
    with open_bag(path) as bag:
        blocks = bag.blocks

        def counted(topics, *, start_ns=None, stop_ns=None):  # type: ignore[no-untyped-def]
            for block in blocks(topics, start_ns=start_ns, stop_ns=stop_ns):
                reads.append((tuple(sorted(topics)), start_ns, stop_ns, len(block)))
                yield block

        bag.blocks = counted  # type: ignore[method-assign]
        plan = plan_bag(bag)
    assert plan.description == ARM.read_text() and plan.tree is not None  # through Bag.last, not a pass
    assert plan.tree.robot.name == "arm6" and plan.fixed_frame == "odom"
    # only /tf_static whole, and the display topics (/map) past the look-ahead until 16 messages are found (a
    # count and a byte budget bound that read, not a time); everything else a bounded stretch
    for topics, start, stop, _ in reads:
        assert topics in (("/tf_static",), ("/map",)) or (
            start is not None and stop is not None and stop - start <= max(LOOKAHEAD_NS, TF_SAMPLE_NS)
        ), (topics, start, stop)
    assert sum(n for *_, n in reads) < 500  # of the 1,505 messages
    assert plan.preview_joints is not None and plan.preview_joints.times_ns[-1] < T0 + LOOKAHEAD_NS
    assert plan.moving_tf is not None and plan.moving_tf.times_ns[-1] > T0 + 9 * S  # sampled over the whole bag
    assert plan.static_tf is not None and plan.static_tf.children == ("camera",)
    assert plan.replay is not None and plan.replay.segments == (
        Segment(("/map", "/joint_states", "/tf"), T0, T0 + 10 * S + 1),
    )
    assert plan.seek_messages == () and plan.replay.span == (T0, T0 + 10 * S)


def test_a_start_offset_keeps_the_state_before_it(tmp_path: Path) -> None:
    path = _long_bag(tmp_path / "long")
    offset = T0 + 5 * S
    with open_bag(path) as bag:
        plan = plan_bag(bag, choice=BagChoice(start_offset_s=5.0))
        assert plan.replay is not None
        assert plan.replay.segments == (
            Segment(("/joint_states", "/tf"), offset - PREROLL_NS, offset),  # the state before the seek
            Segment(("/map", "/joint_states", "/tf"), offset, T0 + 10 * S + 1),
        )
        windows = list(plan.windows(1000))
    assert plan.replay.span == (offset, T0 + 10 * S)
    # the latest map before the offset is shown first (the one at 3 s, not 1 s or 7 s), with its bytes
    assert [(m.time_ns, m.topic, m.msgtype, bytes(m.data)) for m in plan.seek_messages] == [
        (T0 + 3 * S + 5, "/map", MAP, occupancy_grid())
    ]
    assert plan.static_tf is not None and plan.static_tf.children == ("camera",)  # /tf_static whatever the offset
    # the transforms before the offset are replayed first: the last of them (x = 4.98 m) holds at the offset
    tf = [w.tf for w in windows if w.tf is not None]
    times = np.concatenate([r.times_ns for r in tf])
    x = np.concatenate([r.translation[:, 0] for r in tf])
    before = times < offset
    assert before.any() and times[before][-1] == T0 + 249 * 20 * MS + 1 and x[before][-1] == 249 / 50
    assert times[~before][0] == offset + 1 and x[~before][0] == 250 / 50
    assert [m.time_ns for w in windows for m in w.displays] == [T0 + 7 * S + 5]  # maps after it, in the pass
    assert plan.preview_joints is not None and plan.preview_joints.times_ns[0] >= offset


def test_topics_and_offsets_the_bag_cannot_give_are_one_line(tmp_path: Path) -> None:
    path = _long_bag(tmp_path / "long")
    with open_bag(path) as bag:
        with pytest.raises(BagError) as info:
            plan_bag(bag, choice=BagChoice(topics=("/tf", "/scan")))
        assert str(info.value) == (
            f"{path}: no topic /scan in this bag; its 5 topics: /joint_states, /map, /robot_description, /tf, "
            f"/tf_static (--bag {path} --list shows them all)"
        )
        with pytest.raises(BagError, match=r"start offset 10.5 s is past the bag's end \(it lasts 10.0 s\)"):
            plan_bag(bag, choice=BagChoice(start_offset_s=10.5))
        only = plan_bag(bag, choice=BagChoice(topics=("/tf",)))
        everything = plan_bag(bag)
    assert only.replay is not None and only.replay.segments == (Segment(("/tf",), T0, T0 + 10 * S + 1),)
    assert only.displays == {} and only.static_tf is None and only.tree is not None  # the description still read
    assert not only.moves_robot and everything.moves_robot  # without /joint_states the robot stands still


def test_start_offset_and_topics_on_the_command_line(tmp_path: Path) -> None:
    path = _long_bag(tmp_path / "long")
    out = tmp_path / "seek.rrd"
    result = cli("--bag", str(path), "--start-offset", "5", "--topics", "/tf", "/map", "--save", str(out))
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    base = tf_by_child(recording)["base_link"]
    assert base.times[0] < T0 + 5 * S <= base.times[-1]  # the state before the offset, then the rest
    assert "/map" in recording
    for args, problem in [
        (["--start-offset", "11"], "past the bag's end"),
        (["--topics", "/scan"], "no topic /scan in this bag; its 5 topics: /joint_states, /map"),
    ]:
        bad = cli("--bag", str(path), *args, "--save", str(tmp_path / "bad.rrd"))
        lines = bad.stderr.strip().splitlines()
        assert bad.returncode == 2 and len(lines) == 1 and problem in lines[0], bad.stderr
        assert not (tmp_path / "bad.rrd").exists()


def test_topics_replays_exactly_the_topics_named_as_ros2_bag_play_does(tmp_path: Path) -> None:
    """Issue 33, finding 4: ``--topics /joint_states`` replays no transform of the bag; a user who wants them
    names /tf (and /tf_static). The robot's model still comes from /robot_description (its set-up, not replayed
    data). fleetbags.walk_bag: odom → axis on /tf (9 samples), map → odom on /tf_static."""
    from fleetbags import walk_bag

    bag = walk_bag(tmp_path / "walk")
    bag_edges = {"axis"}  # the children /tf moves; "odom" is /tf_static's child
    seen = {}
    for topics in (["/joint_states"], ["/joint_states", "/tf"], ["/joint_states", "/tf", "/tf_static"]):
        out = tmp_path / f"{len(topics)}.rrd"
        result = cli("--bag", str(bag), "--topics", *topics, "--save", str(out))
        assert result.returncode == 0, result.stderr
        recording = read_recording(out)
        moving = tf_by_child(recording)
        assert len(moving["head"].times) == 9  # the robot moves by its joint states in every run
        seen[len(topics)] = (bag_edges & set(moving), "/tf_static/odom" in recording)
    assert seen == {1: (set(), False), 2: ({"axis"}, False), 3: ({"axis"}, True)}
    help_text = cli("--help").stdout
    assert "name /tf and /tf_static too" in " ".join(help_text.split())


def test_a_bag_whose_plots_start_first_opens_in_its_scans_frame(tmp_path: Path) -> None:
    """The cdrr rehab bag's shape (found on it after logs and plots joined the displays): no TF, no robot, numbers
    (std_msgs Int32, plotted) at 100 Hz from the start and a scan in ``world`` only after 3 s. The view opens in
    ``world`` (RViz would need Fixed Frame set to it): plots and log lines frame nothing, so they neither fill the
    preview nor stop it looking past the look-ahead. On the merged code before this fix it opened in ``odom``."""
    from bagmaker import TS
    from displaybags import laser_scan

    spec = BagSpec(types={"/mes_force": "std_msgs/msg/Int32", "/scan": "sensor_msgs/msg/LaserScan"})
    int32 = TS.types["std_msgs/msg/Int32"]
    for k in range(600):  # 6 s of numbers at 100 Hz
        spec.add("/mes_force", T0 + k * 10 * MS, bytes(TS.serialize_cdr(int32(data=k), "std_msgs/msg/Int32")))
    for k in range(5):  # scans from 3 s on
        t = T0 + (3000 + 200 * k) * MS
        spec.add("/scan", t, laser_scan(t // 1_000_000_000, t % 1_000_000_000, frame="world"))
    with open_bag(write_bag(tmp_path / "rehab", spec)) as bag:
        assert plan_bag(bag).fixed_frame == "world"
