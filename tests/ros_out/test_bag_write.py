"""BagWriter: what it writes, read back by rosbags' own reader and deserializer (independent of our reader), and
by ours; atomic; transient-local where robot_state_publisher offers it."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest
from bagmaker import TS
from rosbags.interfaces import QosDurability
from rosbags.rosbag2 import Reader

from r2d2_viz.errors import BagError
from r2d2_viz.ros_out.bag_write import BagWriter, StaticTransform
from r2d2_viz.sources.bag_joints import read_robot_description
from r2d2_viz.sources.bag_tf import concatenate
from r2d2_viz.sources.bags.bag import Bag, open_bag
from r2d2_viz.sources.base import FrameTrack, SampleChunk, TfRecords
from r2d2_viz.sources.plan import plan_bag
from r2d2_viz.sources.playback import BagPass, Segment, bag_topics_read

JOINTS = ["swivel", "tilt", "periscope"]
URDF = "<robot name='r2d2'><link name='base_link'/></robot>"
STATIC = [StaticTransform("base_link", "camera", (0.1, 0.0, 0.3), (0.0, 0.0, 0.0, 1.0))]


def _read(bag: Bag, joints: Sequence[str]) -> tuple[list[SampleChunk], TfRecords | None, TfRecords | None]:
    """By our reader: the joint states and /tf of the bag's one pass, /tf_static as the run's plan reads it."""
    topics = bag_topics_read(bag, joints, {})
    windows = list(BagPass(bag, [Segment(topics)], actuated=joints, displays={}).windows(100))
    chunks = [w.joints for w in windows if w.joints is not None]
    return chunks, plan_bag(bag).static_tf, concatenate([w.tf for w in windows if w.tf is not None])


def _run(n: int = 250, seed: int = 1):
    rng = np.random.default_rng(seed)
    times = np.arange(n, dtype=np.int64) * 33_333_333
    positions = rng.normal(size=(n, 3))
    positions[5, 1] = np.nan  # a sample that does not give tilt
    positions[9, :2] = np.nan
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    track = FrameTrack("odom", "base_link", rng.normal(size=(n, 3)), q)
    return times, positions, track


def _write(path: Path, chunks: int = 3, start_ns: int = 1_700_000_000_000_000_000) -> tuple:
    times, positions, track = _run()
    with BagWriter(path, robot_description=URDF, static_transforms=STATIC, clock="duration", start_ns=start_ns) as w:
        for part in np.array_split(np.arange(len(times)), chunks):
            sub = FrameTrack(track.parent, track.child, track.translation[part], track.quat_xyzw[part])
            w.write_samples(times[part], JOINTS, positions[part], [sub])
    return times + start_ns, positions, track


def test_rosbags_reads_back_every_value(tmp_path: Path) -> None:
    path = tmp_path / "lap.mcap"
    times, positions, track = _write(path)
    assert sorted(p.name for p in path.iterdir()) == ["lap.mcap", "metadata.yaml"]
    assert [p.name for p in tmp_path.iterdir()] == ["lap.mcap"]  # no temporary left beside it
    got: dict[str, list] = {"/joint_states": [], "/tf": [], "/tf_static": [], "/robot_description": []}
    with Reader(path) as reader:
        assert reader.message_count == 2 * len(times) + 2
        qos = {c.topic: c.ext.offered_qos_profiles[0].durability for c in reader.connections}
        for conn, t, data in reader.messages():
            got[conn.topic].append((t, TS.deserialize_cdr(data, conn.msgtype)))
    assert qos["/robot_description"] == qos["/tf_static"] == QosDurability.TRANSIENT_LOCAL
    assert qos["/joint_states"] == qos["/tf"] == QosDurability.VOLATILE
    assert [m.data for _, m in got["/robot_description"]] == [URDF]
    ((t_static, tf_static),) = got["/tf_static"]
    (static,) = tf_static.transforms
    assert (static.header.frame_id, static.child_frame_id, static.transform.translation.z) == (
        "base_link",
        "camera",
        0.3,
    )
    assert t_static == times[0]
    for k, (t, msg) in enumerate(got["/joint_states"]):
        assert t == times[k] == msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec  # header = recording time
        given = ~np.isnan(positions[k])
        assert msg.name == [j for j, g in zip(JOINTS, given, strict=True) if g]
        np.testing.assert_array_equal(msg.position, positions[k][given])
        assert len(msg.velocity) == len(msg.effort) == 0
    for k, (t, msg) in enumerate(got["/tf"]):
        (tf,) = msg.transforms
        assert t == times[k] and (tf.header.frame_id, tf.child_frame_id) == ("odom", "base_link")
        v, r = tf.transform.translation, tf.transform.rotation
        np.testing.assert_array_equal(
            [v.x, v.y, v.z, r.x, r.y, r.z, r.w], np.hstack([track.translation[k], track.quat_xyzw[k]])
        )


def test_our_reader_reads_it_back(tmp_path: Path) -> None:
    times, positions, track = _write(tmp_path / "run.mcap")  # a rosbag2 directory named like a file
    with open_bag(tmp_path / "run.mcap") as bag:
        assert read_robot_description(bag) == URDF
        chunks, static, moving = _read(bag, JOINTS)
    assert static is not None and moving is not None
    np.testing.assert_array_equal(np.concatenate([c.times_ns for c in chunks]), times)
    np.testing.assert_array_equal(np.vstack([c.positions for c in chunks]), positions)  # NaN where not given
    np.testing.assert_array_equal(moving.translation, track.translation)
    np.testing.assert_array_equal(moving.quat_xyzw, track.quat_xyzw)
    assert static.children == ("camera",) and static.static


def test_timestamp_clock_keeps_times(tmp_path: Path) -> None:
    t = np.array([1_600_000_000_000_000_000, 1_600_000_000_500_000_000], dtype=np.int64)
    with BagWriter(tmp_path / "b", robot_description=URDF) as w:
        w.write_samples(t, ["a"], np.array([[1.0], [2.0]]))
    with Reader(tmp_path / "b") as reader:
        assert [x for c, x, _ in reader.messages() if c.topic == "/joint_states"] == t.tolist()


def test_failure_inside_leaves_nothing_and_keeps_an_old_bag(tmp_path: Path) -> None:
    path = tmp_path / "keep.mcap"
    _write(path)
    before = {p.name: p.read_bytes() for p in path.iterdir()}
    with pytest.raises(RuntimeError), BagWriter(path, robot_description="<robot name='other'/>") as w:
        w.write_samples(np.array([0], dtype=np.int64), ["a"], np.array([[1.0]]))
        raise RuntimeError("interrupted")
    assert {p.name: p.read_bytes() for p in path.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["keep.mcap"]


def test_an_existing_bag_is_replaced_when_done(tmp_path: Path) -> None:
    path = tmp_path / "b"
    _write(path)
    with BagWriter(path, robot_description="<robot name='new'/>") as w:
        w.write_samples(np.array([0], dtype=np.int64), ["a"], np.array([[1.0]]))
    with open_bag(path) as bag:
        assert read_robot_description(bag) == "<robot name='new'/>"
    assert [p.name for p in tmp_path.iterdir()] == ["b"]


def test_never_clobbers_what_is_not_a_bag(tmp_path: Path) -> None:
    (tmp_path / "notes.mcap").write_text("mine")
    (tmp_path / "photos").mkdir()
    for target in ("notes.mcap", "photos"):
        with pytest.raises(BagError, match="not a rosbag2 directory; not overwriting"):
            BagWriter(tmp_path / target, robot_description=URDF)
    with pytest.raises(BagError, match="does not exist"):
        BagWriter(tmp_path / "no" / "such" / "dir.mcap", robot_description=URDF)
    assert (tmp_path / "notes.mcap").read_text() == "mine"


def test_a_run_without_samples_still_has_the_robot(tmp_path: Path) -> None:
    with BagWriter(tmp_path / "b", robot_description=URDF, static_transforms=STATIC, start_ns=5) as w:
        pass
    with open_bag(w.path) as bag:
        assert read_robot_description(bag) == URDF
        chunks, static, moving = _read(bag, JOINTS)
    assert chunks == [] and moving is None and static is not None and static.children == ("camera",)


def test_the_tutorial_lap_round_trips_exactly(tmp_path: Path) -> None:
    """A whole lap of the tutorial motion (1,440 samples, odom → axis track) written chunk by chunk and read
    back: the same positions, the same track, times shifted by the recording's start; the same URDF text."""
    from r2d2_viz.robot.model import default_urdf_path, load_urdf
    from r2d2_viz.sources.motion import TutorialMotion

    urdf_path = default_urdf_path()
    robot = load_urdf(urdf_path)
    motion = TutorialMotion(robot, n_samples=1440)
    chunks = list(motion.chunks(500))
    start = 1_700_000_000_000_000_000
    with BagWriter(
        tmp_path / "lap.mcap", robot_description=urdf_path.read_text(), clock="duration", start_ns=start
    ) as w:
        for c in chunks:
            w.write_samples(c.times_ns, c.joints, c.positions, c.frames)
    with open_bag(tmp_path / "lap.mcap") as bag:
        back, static, tf = _read(bag, motion.joints)
        assert static is None and tf is not None
        assert read_robot_description(bag) == urdf_path.read_text()
    times = np.concatenate([c.times_ns for c in chunks])
    np.testing.assert_array_equal(np.concatenate([c.times_ns for c in back]), times + start)
    assert all(c.joints == motion.joints for c in back)
    np.testing.assert_array_equal(np.vstack([c.positions for c in back]), np.vstack([c.positions for c in chunks]))
    (track,) = chunks[0].frames
    assert set(zip(tf.parents, tf.children, strict=True)) == {(track.parent, track.child)}
    np.testing.assert_array_equal(tf.translation, np.vstack([c.frames[0].translation for c in chunks]))
    np.testing.assert_array_equal(tf.quat_xyzw, np.vstack([c.frames[0].quat_xyzw for c in chunks]))
