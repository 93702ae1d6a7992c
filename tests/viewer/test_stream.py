"""RobotStream's order of calls: a chunk sent in pieces equals it sent whole; a subset of joints keeps the others;
a timestamp clock makes a timestamp timeline."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
from rerun.chunk import RrdReader
from rrd import read_recording, tf_by_child

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import default_urdf_path, load_urdf
from r2d2_viz.sources.base import SampleChunk
from r2d2_viz.sources.live.source import LiveBatch
from r2d2_viz.sources.motion import make_motion
from r2d2_viz.viewer.stream import PLOT_PERIOD_NS, RobotStream, robot_namespaces


def _record(out: Path, send, gather: bool = False) -> dict:
    rec = rr.RecordingStream("test")
    rec.save(out)
    tree = compile_tree(load_urdf(default_urdf_path()))
    motion = make_motion(tree.robot, "tutorial", n_samples=40)
    stream = RobotStream(rec, tree, frames=motion.frames, clock=motion.clock, warn=lambda _: None, gather=gather)
    stream.log_static()
    send(stream, next(motion.chunks(40)))
    stream.finish()
    rec.flush()
    rec.disconnect()
    return read_recording(out)


def test_pieces_equal_the_whole(tmp_path: Path) -> None:
    def whole(stream, chunk):
        stream.send(stream.prepare(chunk))

    def pieces(stream, chunk):
        prepared = stream.prepare(chunk)
        for start in range(0, 40, 3):  # as a live run sends: a few samples at a time
            stream.send(prepared, start, start + 3)

    a, b = _record(tmp_path / "a.rrd", whole), _record(tmp_path / "b.rrd", pieces)
    for child in ("axis", "body", "head", "rod"):
        ra, rb = tf_by_child(a)[child], tf_by_child(b)[child]
        assert ra.times == rb.times and ra.temporal["Transform3D:translation"] == rb.temporal["Transform3D:translation"]
    va, vb = a["/joints/limited"], b["/joints/limited"]
    assert va.times == vb.times and va.temporal["Scalars:scalars"] == vb.temporal["Scalars:scalars"]


def _tf_chunks(path: Path) -> int:
    reader = RrdReader(path)
    return sum(1 for c in reader.stream(store=reader.recordings()[0]) if c.entity_path == "/tf" and not c.is_static)


def test_a_run_without_a_live_viewer_gathers_its_transforms_and_loses_none(tmp_path: Path) -> None:
    """Sent a sample at a time, as a paced save sends them: every sample's transforms are in the file, in a chunk
    every PLOT_PERIOD_NS of samples rather than one per sample (Rerun keeps ~3 kB per chunk until the file
    closes)."""

    def one_by_one(stream, chunk):
        prepared = stream.prepare(chunk)
        for k in range(len(chunk)):
            stream.send(prepared, k, k + 1)

    a, b = tmp_path / "each.rrd", tmp_path / "gathered.rrd"
    each, gathered = _record(a, one_by_one), _record(b, one_by_one, gather=True)
    for child in ("axis", "body", "head", "rod"):
        ra, rb = tf_by_child(each)[child], tf_by_child(gathered)[child]
        assert len(ra.times) == 40 and ra.times == rb.times
        assert ra.temporal["Transform3D:quaternion"] == rb.temporal["Transform3D:quaternion"]
    span_s = (tf_by_child(each)["body"].times[-1] - tf_by_child(each)["body"].times[0]) * 1e-9
    assert _tf_chunks(a) == 40 and _tf_chunks(b) <= span_s / (PLOT_PERIOD_NS * 1e-9) + 2


def test_a_subset_of_joints_keeps_the_others_and_timestamps(tmp_path: Path) -> None:
    out = tmp_path / "s.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    tree = compile_tree(load_urdf(default_urdf_path()))
    stream = RobotStream(rec, tree, clock="timestamp", warn=lambda _: None)
    stream.log_static()
    t0 = 1_700_000_000_000_000_000
    first = SampleChunk(np.array([t0], dtype=np.int64), ("swivel", "tilt", "periscope"), np.array([[0.5, -0.2, -0.1]]))
    then = SampleChunk(np.array([t0 + 10, t0 + 20], dtype=np.int64), ("tilt",), np.array([[-0.3], [np.nan]]))
    for chunk in (first, then):
        stream.send(stream.prepare(chunk))
    stream.finish()
    rec.flush()
    rec.disconnect()
    plot = read_recording(out)["/joints/limited"]
    names = read_recording(out)["/joints/limited"].static["SeriesLines:names"][-1]
    rows = [dict(zip(names, v, strict=True)) for v in plot.temporal["Scalars:scalars"]]
    assert plot.times == [t0, t0 + 10, t0 + 20]
    assert [r["tilt"] for r in rows] == [-0.2, -0.3, -0.3] and [r["periscope"] for r in rows] == [-0.1] * 3
    swivel = read_recording(out)["/joints/continuous"].temporal["Scalars:scalars"]
    assert [v[0] for v in swivel] == [0.5, 0.5, 0.5]


def test_several_robots_are_named_and_one_keeps_the_single_robot_names() -> None:
    two = [LiveBatch(robot_descriptions=[("/robot2", "<robot/>")]), LiveBatch(robot_descriptions=[("/robot1", "x")])]
    assert robot_namespaces(two) == ("/robot1", "/robot2")
    assert robot_namespaces([LiveBatch(descriptions=["<robot/>"]), *two[:1]]) == ("", "/robot2")
    assert robot_namespaces(two[:1]) == () and robot_namespaces([LiveBatch(descriptions=["x"])]) == ()
