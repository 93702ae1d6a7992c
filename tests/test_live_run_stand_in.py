"""A live run on a stand-in graph (no DDS): the benchmark hook (``R2D2_VIZ_PACING_LOG``: one ``topic
lateness_seconds`` line per message handed to Rerun, nothing at all when unset), and what comes before the robot is
known or after the settle — joint states held until then, robots described late."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sources.live.test_source import JS, FakeGraph, LateGraph, _js

import r2d2_viz.live_run as live_run
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.pacing import PACING_LOG_ENV
from r2d2_viz.sources.live.dds import Publication, Sample
from r2d2_viz.viewer.sinks import SinkConfig

URDF = """<robot name="one"><link name="a"/><link name="b"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""
IMAGE = "sensor_msgs/msg/Image"


@dataclass
class Config:
    urdf: Path | None
    sink: SinkConfig
    duration: float | None = 0.4
    mappings: dict[str, str] = field(default_factory=dict)
    package_paths: tuple[str, ...] = ()
    time: Any = "receive"
    fixed_frame: str | None = None
    rviz: Path | None = None
    tool_topics: tuple[tuple[str, str], ...] = ()
    video: Any = None
    tf_tree: bool = False
    show: frozenset[str] = frozenset()
    motion: str | None = None


def _image() -> bytes:
    t = typestore("jazzy").types
    msg = t[IMAGE](
        header=t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="cam"),
        height=2, width=2, encoding="rgb8", is_bigendian=0, step=6, data=np.zeros(12, dtype=np.uint8),
    )  # fmt: skip
    return bytes(typestore("jazzy").serialize_cdr(msg, IMAGE))


def _run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> int:
    monkeypatch.setattr(live_run, "SETTLE_SECONDS", 0.1)
    urdf = tmp_path / "one.urdf"
    urdf.write_text(URDF)
    graph = FakeGraph()
    graph.pubs = [Publication("/joint_states", JS, False, False), Publication("/cam/image", IMAGE, False, False)]
    sent_ns = time.time_ns() - 2_000_000_000  # written two seconds ago
    graph.queue = [Sample("/joint_states", JS, sent_ns + k, _js(["j"], [0.1 * k])) for k in range(3)]
    graph.queue.append(Sample("/cam/image", IMAGE, sent_ns, _image()))
    config = Config(urdf, SinkConfig(save=tmp_path / "out.rrd"))
    samples, _, _ = live_run.run_on(config, graph, threading.Event())  # type: ignore[arg-type]
    return samples


def test_each_message_handed_to_rerun_is_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    log = tmp_path / "lateness.txt"
    monkeypatch.setenv(PACING_LOG_ENV, str(log))
    assert _run(tmp_path, monkeypatch) == 3
    lines = [line.split() for line in log.read_text().splitlines()]
    assert sorted(topic for topic, _ in lines) == ["/cam/image", "/joint_states", "/joint_states", "/joint_states"]
    for _, seconds in lines:
        assert 2.0 <= float(seconds) < 30.0


def test_nothing_written_when_unset(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(PACING_LOG_ENV, raising=False)
    assert _run(tmp_path, monkeypatch) == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.urdf", "out.rrd"]


def test_joint_states_received_while_settling_are_shown_when_the_run_ends_there(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run stopped (or out of time) right after the settle: the joint states that came before the robot was
    loaded are held by the source until it is; the end of the run hands them out, it does not drop them
    (seen in CI: a 0.4 s run on a busy machine received 3 joint states and showed 0)."""
    stop = threading.Event()

    class StopAfterFirstPoll(FakeGraph):
        def poll(self) -> list[Sample]:
            stop.set()
            return super().poll()

    urdf = tmp_path / "one.urdf"
    urdf.write_text(URDF)
    graph = StopAfterFirstPoll()
    graph.pubs = [Publication("/joint_states", JS, False, False)]
    graph.queue = [Sample("/joint_states", JS, 10**9 + k, _js(["j"], [0.1 * k])) for k in range(3)]
    config = Config(urdf, SinkConfig(save=tmp_path / "out.rrd"), duration=None)
    samples, interrupted, _ = live_run.run_on(config, graph, stop)  # type: ignore[arg-type]
    assert interrupted
    assert samples == 3


def test_robots_described_after_the_settle_are_several_robots(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two namespaced robots whose descriptions come only after the settle (a busy machine, nodes started later):
    still a run of several robots, each named when no transform places it (seen in a loaded run: one robot's
    line was missing, the settle having seen none of them)."""
    monkeypatch.setattr(live_run, "SETTLE_SECONDS", 0.1)

    graph = LateGraph()
    string = "std_msgs/msg/String"
    store = typestore("jazzy")
    text = bytes(store.serialize_cdr(store.types[string](data=URDF), string))
    graph.pubs = [Publication(f"/{ns}/robot_description", string, True, True) for ns in ("robot1", "robot2")]
    graph.queue = [Sample(f"/{ns}/robot_description", string, 10**9, text) for ns in ("robot1", "robot2")]
    config = Config(None, SinkConfig(save=tmp_path / "out.rrd"), duration=1.0)
    live_run.run_on(config, graph, threading.Event())  # type: ignore[arg-type]
    err = capsys.readouterr().err
    assert err.count("robot /robot1: no recorded transform places its root") == 1, err
    assert err.count("robot /robot2: no recorded transform places its root") == 1, err


def test_no_entity_has_arrow_colours_without_vectors_when_no_joint_states_come(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A live run of a robot with a prismatic joint whose graph never publishes ``/joint_states`` (seen: the 3D
    view's error badge "Component 'Arrows3D:vectors' does not exist on the entity" on ``/tf``, the moving arrows'
    colours logged up front and their vectors never). Read back: every entity with arrow colours has vectors."""
    from rrd import read_recording

    monkeypatch.setattr(live_run, "SETTLE_SECONDS", 0.1)
    urdf = tmp_path / "slide.urdf"
    urdf.write_text(
        """<robot name="slide"><link name="a"/><link name="b"/>
<joint name="s" type="prismatic"><parent link="a"/><child link="b"/><origin xyz="0 0 0.5"/><axis xyz="1 0 0"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""
    )
    graph = FakeGraph()
    graph.pubs = [Publication("/cam/image", IMAGE, False, False)]
    graph.queue = [Sample("/cam/image", IMAGE, time.time_ns(), _image())]
    config = Config(urdf, SinkConfig(save=tmp_path / "out.rrd"))
    samples, _, _ = live_run.run_on(config, graph, threading.Event())  # type: ignore[arg-type]
    assert samples == 0
    recording = read_recording(tmp_path / "out.rrd")
    half = []
    for entity, rows in recording.items():
        names = {*rows.static, *rows.temporal}
        if any("Arrows3D:colors" in n for n in names) and not any("Arrows3D:vectors" in n for n in names):
            half.append(entity)
    assert half == [], {e: sorted({*recording[e].static, *recording[e].temporal}) for e in half}
