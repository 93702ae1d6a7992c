"""The live source against a stand-in graph (no DDS): subscriptions as topics appear, wrong types refused, and
malformed joint states, transforms and descriptions counted and said once per kind — never a crash."""

from __future__ import annotations

import struct
import time

import numpy as np

from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.sources.live.dds import Publication, Sample
from r2d2_viz.sources.live.source import LiveSource

JS, TF, STR = "sensor_msgs/msg/JointState", "tf2_msgs/msg/TFMessage", "std_msgs/msg/String"


class FakeGraph:
    def __init__(self) -> None:
        self.pubs: list[Publication] = []
        self.queue: list[Sample] = []
        self.dropped: dict[str, int] = {}
        self.subscribed: list[tuple[str, str]] = []

    def publications(self) -> list[Publication]:
        return list(self.pubs)

    def subscribe(self, topic: str, ros_type: str, *, wait: float = 1.0) -> Publication:
        self.subscribed.append((topic, ros_type))
        return Publication(topic, ros_type, False, False)

    def poll(self) -> list[Sample]:
        out, self.queue = self.queue, []
        return out

    def wait(self, timeout: float) -> bool:
        time.sleep(timeout)
        return bool(self.queue)


class LateGraph(FakeGraph):
    """A graph whose samples come only after the run's settle (a busy machine, nodes started later): nothing is
    polled until the run first waits (the settle never waits)."""

    waited = False

    def poll(self) -> list[Sample]:
        return super().poll() if self.waited else []

    def wait(self, timeout: float) -> bool:
        self.waited = True
        return super().wait(timeout)


def _js(names: list[str], position: list[float], sec: int = 5) -> bytes:
    t = typestore("jazzy").types
    msg = t[JS](
        header=t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=sec, nanosec=0), frame_id=""),
        name=names,
        position=np.array(position, dtype=np.float64),
        velocity=np.zeros(0),
        effort=np.zeros(0),
    )
    return bytes(typestore("jazzy").serialize_cdr(msg, JS))


def test_topics_subscribed_as_they_appear_and_wrong_types_said_once() -> None:
    graph = FakeGraph()
    source = LiveSource(graph, refresh=1.0)
    graph.pubs = [
        Publication("/joint_states", JS, False, False),
        Publication("/parameter_events", "rcl_interfaces/msg/ParameterEvent", 1, 0),  # no display draws it
    ]
    source.poll(now=0.0)
    assert graph.subscribed == [("/joint_states", JS)]
    scan = "sensor_msgs/msg/LaserScan"
    graph.pubs += [Publication("/scan", scan, False, False), Publication("/tf", STR, False, False)]
    assert source.poll(now=0.5).notes == []  # not re-read before a second has passed
    notes = source.poll(now=1.0).notes
    assert ("/scan", "sensor_msgs/msg/LaserScan") in graph.subscribed
    assert [line for _, line in notes] == [
        "/tf: a publisher of std_msgs/msg/String, not tf2_msgs/msg/TFMessage: not read"
    ]
    assert source.poll(now=2.0).notes == []


def test_malformed_joint_states_counted_and_good_ones_land() -> None:
    graph = FakeGraph()
    source = LiveSource(graph)
    source.set_joints(["a", "b"])
    absurd = b"\x00\x01\x00\x00" + struct.pack("<iI", 1, 0) + struct.pack("<I", 0x7FFFFFF0) + b"x" * 16
    bad = [
        b"\x00\x01\x00\x00\xff\xff",
        absurd,
        _js(["a", "b"], [float("nan"), 1.0]),
        _js(["a", "b"], [1.0]),
        _js([f"n{i}" for i in range(10_000)], [0.0] * 10_000),
    ]
    good = [_js(["a", "b"], [0.1 * k, -0.1 * k], sec=10 + k) for k in range(5)]
    graph.queue = [Sample("/joint_states", JS, 100 + i, d) for i, d in enumerate([*bad, *good])]
    batch = source.poll(now=0.0)
    assert batch.joints is not None
    positions = batch.joints.positions
    np.testing.assert_array_equal(positions[-5:], [[0.1 * k, -0.1 * k] for k in range(5)])
    assert np.isnan(positions[0, 0]) and positions[0, 1] == 1.0  # NaN: the joint keeps its last value
    keys = [key for key, _ in batch.notes]
    assert sorted(keys) == sorted(f"/joint_states {k}" for k in ("unknown", "skipped", "undecodable", "nonfinite"))
    graph.queue = [Sample("/joint_states", JS, 200, bad[3])]
    assert source.poll(now=0.1).notes == []  # said once; counted
    problems = dict(source.problems())
    assert "skipped 2 messages whose name and position lengths differ" in [p for _, p in source.problems()]
    assert problems


def test_joint_states_before_the_robot_wait_bounded_and_a_bad_description_is_a_note() -> None:
    graph = FakeGraph()
    source = LiveSource(graph)
    graph.queue = [Sample("/joint_states", JS, i, _js(["a"], [float(i)])) for i in range(1500)]
    graph.queue.append(Sample("/robot_description", STR, 0, b"\x00\x01\x00\x00\xff\xff\xff\x7f"))
    batch = source.poll(now=0.0)
    assert batch.joints is None and batch.descriptions == []
    assert [k for k, _ in batch.notes] == ["description /robot_description"]
    source.set_joints(["a"])
    chunk = source.poll(now=0.1).joints
    assert chunk is not None and len(chunk) == 1000  # the newest 1000 kept
    assert chunk.positions[0, 0] == 500.0


def test_dropped_samples_said_once_and_counted() -> None:
    graph = FakeGraph()
    source = LiveSource(graph)
    graph.dropped = {"/scan": 3}
    assert [k for k, _ in source.poll(now=0.0).notes] == ["dropped /scan"]
    graph.dropped = {"/scan": 7}
    assert source.poll(now=0.1).notes == []
    assert ("/scan", "7 messages dropped: the viewer fell behind") in source.problems()


def test_non_finite_transforms_skipped() -> None:
    store = typestore("jazzy")
    t = store.types
    stamped = t["geometry_msgs/msg/TransformStamped"](
        header=t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="odom"),
        child_frame_id="base",
        transform=t["geometry_msgs/msg/Transform"](
            translation=t["geometry_msgs/msg/Vector3"](x=float("nan"), y=0.0, z=0.0),
            rotation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
        ),
    )
    data = bytes(store.serialize_cdr(t[TF](transforms=[stamped]), TF))
    graph = FakeGraph()
    source = LiveSource(graph)
    graph.queue = [Sample("/tf", TF, 1, data), Sample("/tf", TF, 2, b"\x00\x01\x00\x00")]
    batch = source.poll(now=0.0)
    assert batch.tf == []
    assert sorted(k for k, _ in batch.notes) == ["/tf bad", "/tf nonfinite"]


def test_topics_no_display_draws_are_read_for_their_fields_when_their_type_is_known() -> None:
    graph = FakeGraph()
    store = typestore("jazzy")
    source = LiveSource(graph, refresh=1.0, known_types=store.fielddefs)
    graph.pubs = [
        Publication("/joy", "sensor_msgs/msg/Joy", False, False),
        Publication("/mine", "my_msgs/msg/Nobody", False, False),
    ]
    source.poll(now=0.0)
    assert graph.subscribed == [("/joy", "sensor_msgs/msg/Joy")]  # my_msgs: no definition anywhere, not read
    joy = store.types["sensor_msgs/msg/Joy"]
    header = store.types["std_msgs/msg/Header"](store.types["builtin_interfaces/msg/Time"](1, 0), "joy")
    data = bytes(
        store.serialize_cdr(joy(header, np.array([0.5], np.float32), np.array([1], np.int32)), "sensor_msgs/msg/Joy")
    )
    graph.queue = [Sample("/joy", "sensor_msgs/msg/Joy", 7, data)]
    batch = source.poll(now=0.5)
    assert [(m.topic, m.time_ns, m.data) for m in batch.fields] == [("/joy", 7, data)] and not batch.displays
    assert LiveSource(FakeGraph()).known_types == ()  # without known types: display topics only, as before
