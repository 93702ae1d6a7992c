"""Where a run starts on its time line (sources/start.py: where the warnings said as it loads go): a motion's 0, a
bag's first receive time as rosbags' own reader gives it (a seek's pre-roll, header stamps), a live graph's first
message."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from bagmaker import T0, BagSpec, joint_state, string, tf_message, write_bag
from rosbags.highlevel import AnyReader

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import default_urdf_path
from r2d2_viz.robot.xacro_load import load_robot
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.base import SampleChunk, TfRecords
from r2d2_viz.sources.live.dds import Sample
from r2d2_viz.sources.live.source import LiveBatch
from r2d2_viz.sources.motion import make_motion
from r2d2_viz.sources.plan import BagChoice, plan_bag, plan_motion
from r2d2_viz.sources.start import live_start_ns, plan_start_ns

S = 1_000_000_000
JOINTS = ("swivel",)
JS = "sensor_msgs/msg/JointState"


def _bag(path: Path, *, stamp_offset_ns: int = 0) -> Path:
    """The tutorial R2D2 on /robot_description at T0 + 0.5 s, then 10 s of /joint_states and /tf at 10 Hz from
    T0 + 1 s, each stamped ``stamp_offset_ns`` after it was received."""
    spec = BagSpec()
    spec.add("/robot_description", T0 + S // 2, string(default_urdf_path().read_text()))
    for k in range(100):
        t = T0 + S + k * S // 10
        spec.add("/joint_states", t, joint_state(t + stamp_offset_ns, JOINTS, [0.01 * k]))
        spec.add("/tf", t, tf_message([(t + stamp_offset_ns, "odom", "axis", (0.01 * k, 0, 0), (0, 0, 0, 1))]))
    return write_bag(path, spec)


def _first_receive_time(bag: Path) -> int:
    """The bag's first message as rosbags reads it (not r2d2-viz's reader)."""
    with AnyReader([bag]) as reader:
        return int(min(t for _, t, _ in reader.messages()))


def test_a_motion_starts_at_zero() -> None:
    robot = load_robot(default_urdf_path())
    source = make_motion(robot, None, rate=30.0, n_samples=5)
    assert int(next(source.chunks(5)).times_ns[0]) == 0  # its first sample: the duration since the start
    assert plan_start_ns(plan_motion(compile_tree(robot), source, "odom")) == 0


def test_a_bag_starts_at_its_first_message(tmp_path: Path) -> None:
    bag = _bag(tmp_path / "bag")
    first = _first_receive_time(bag)
    assert first == T0 + S // 2  # by hand: the description, half a second in
    with open_bag(bag) as opened:
        assert plan_start_ns(plan_bag(opened)) == first


def test_a_seek_starts_where_its_pre_roll_does(tmp_path: Path) -> None:
    """``--start-offset 7``: the transforms and joint states of the 5 s before it are replayed first (plan.py's
    PREROLL_NS): the run starts 2 s after the bag's first message."""
    bag = _bag(tmp_path / "bag")
    with open_bag(bag) as opened:
        start = plan_start_ns(plan_bag(opened, choice=BagChoice(start_offset_s=7.0)))
    assert start == _first_receive_time(bag) + 2 * S


def test_header_time_starts_at_the_first_stamp(tmp_path: Path) -> None:
    """``--time header``: the time line is the messages' stamps (here an hour after they were received)."""
    bag = _bag(tmp_path / "bag", stamp_offset_ns=3600 * S)
    with open_bag(bag) as opened:
        start = plan_start_ns(plan_bag(opened, time="header"))
    assert start == T0 + S + 3600 * S  # by hand: the first joint state's and transform's stamp


def _chunk(times: list[int]) -> SampleChunk:
    return SampleChunk(np.array(times, dtype=np.int64), JOINTS, np.zeros((len(times), 1)))


def test_a_live_run_starts_at_the_first_message_its_settle_received() -> None:
    tf = TfRecords(np.array([7, 3], dtype=np.int64), ("odom", "odom"), ("a", "b"), np.zeros((2, 3)), np.zeros((2, 4)))
    latched = TfRecords(np.array([1], dtype=np.int64), ("a",), ("c",), np.zeros((1, 3)), np.zeros((1, 4)), static=True)
    batches = [LiveBatch(joints=_chunk([5, 6])), LiveBatch(tf=[latched, tf])]
    assert live_start_ns(batches, now_ns=100) == 3  # the transform at 3: /tf_static's rows hold for all time
    held = LiveBatch(samples=[Sample("/joint_states", JS, 9, b""), Sample("/joint_states", JS, 4, b"")])
    assert live_start_ns([held], now_ns=100) == 4  # joint states held until a robot comes: when they were sent
    assert live_start_ns([LiveBatch(), LiveBatch()], now_ns=100) == 100  # nothing yet: the clock as it starts
