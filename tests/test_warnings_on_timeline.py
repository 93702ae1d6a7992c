"""Every warning a row of the time line (issue 44, item 17): what a run says as it loads — a missing mesh, an
impossible inertia, an ``--rviz`` note, "no robot" — is a ``/warnings`` row at the run's first time on the timeline
the Warnings view shows (the blueprint's time panel's), for batch, live (``--realtime``), ``--bag`` and ``--ros``
runs; nothing on ``/warnings`` is static (a static row is not shown there, and hides the timed ones).

Read back from the saved .rrd with Rerun's own reader (tests/rrd.py). The first times come from elsewhere: a
generated motion's first sample is at 0 (its clock is the duration since the start); a bag's first message is
rosbags' own reader's; a live graph's is the source timestamp of the first message the stand-in graph sent."""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any

import pytest
from bagmaker import T0, BagSpec, joint_state, tf_message, write_bag
from conftest import REPO, cli
from rosbags.highlevel import AnyReader
from rrd import Rows, blueprint_components, read_recording
from sources.live.test_source import JS, FakeGraph, LateGraph, _js
from test_live_run_stand_in import Config

import r2d2_viz.live_run as live_run
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.robot.model import default_urdf_path
from r2d2_viz.sources.live.dds import Publication, Sample
from r2d2_viz.viewer.sinks import SinkConfig

S = 1_000_000_000
RVIZ = REPO / "tests" / "data" / "rviz" / "urdf_tutorial_ros1_urdf.rviz"
MISSING_MESH = "link 'axis': visual #2: mesh file 'meshes/gone.stl' not found; visual skipped"
INERTIA = "link 'leg1': <inertial>: "
RVIZ_NOTE = "urdf_tutorial_ros1_urdf.rviz: Grid / Plane Cell Count 10"
NO_ROBOT = "no --urdf and no /robot_description"
LOADED = (MISSING_MESH, INERTIA, RVIZ_NOTE)
STRING = "std_msgs/msg/String"


def _urdf(tmp_path: Path) -> Path:
    """The tutorial R2D2 with a mesh that is not there (on ``axis``) and an inertia no body has (``leg1``'s izz is
    more than ixx + iyy: the triangle inequality fails)."""
    text = default_urdf_path().read_text()
    gone = '<visual><geometry><mesh filename="meshes/gone.stl"/></geometry></visual></link><link name="leg1">'
    text = text.replace('</link><link name="leg1">', gone, 1)
    bad = '<inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-2" />'
    text = text.replace('<inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3" />', bad, 1)
    path = tmp_path / "broken_r2d2.urdf"
    path.write_text(text)
    return path


def _bag(path: Path) -> Path:
    """The R2D2's swivel turning for 2 s at 10 Hz and its axis driving along x, from T0 + 1 s; no description."""
    spec = BagSpec()
    for k in range(20):
        t = T0 + S + k * S // 10
        spec.add("/joint_states", t, joint_state(t, ("swivel",), [0.1 * k]))
        spec.add("/tf", t, tf_message([(t, "odom", "axis", (0.01 * k, 0, 0), (0, 0, 0, 1))]))
    return write_bag(path, spec)


def _first_receive_time(bag: Path) -> int:
    with AnyReader([bag]) as reader:
        return int(min(t for _, t, _ in reader.messages()))


def _record(out: Path, *args: str) -> tuple[dict[str, Rows], str]:
    run = cli(*args, "--save", str(out))
    assert run.returncode == 0, run.stderr
    return read_recording(out), run.stderr


def _assert_at_first_time(recording: dict[str, Rows], out: Path, first_ns: int, said: tuple[str, ...]) -> None:
    """Each of ``said`` a ``/warnings`` row at ``first_ns`` on the timeline the Warnings view shows; none static."""
    views = blueprint_components(out)
    [view] = [v for v in views.values() if v.get("ViewBlueprint:display_name") == ["Warnings"]]
    assert view["ViewBlueprint:class_identifier"] == ["TextLog"] and view["ViewBlueprint:space_origin"] == ["/warnings"]
    assert views["/time_panel"]["TimePanelBlueprint:timeline"] == ["time"]  # read_recording's times: that timeline
    rows = recording["/warnings"]
    assert not rows.static, rows.static
    at = {text[0] for t, text in zip(rows.times, rows.temporal["TextLog:text"], strict=True) if t == first_ns}
    for line in said:
        assert any(line in text for text in at), (line, rows.times, rows.temporal["TextLog:text"])
    assert min(t for r in recording.values() for t in r.times) == first_ns  # nothing before the run's start


@pytest.mark.parametrize("paced", [False, True], ids=["batch", "live"])
def test_a_motions_load_time_warnings_at_its_start(tmp_path: Path, paced: bool) -> None:
    out = tmp_path / "out.rrd"
    args = ["--urdf", str(_urdf(tmp_path)), "--inertia", "--rviz", str(RVIZ), "--duration", "0.5"]
    recording, stderr = _record(out, *args, *(["--realtime"] if paced else []))
    assert all(line in stderr for line in LOADED), stderr  # said on the terminal as before
    assert recording["/tf"].times[0] == 0  # the motion's first sample
    _assert_at_first_time(recording, out, 0, LOADED)


def test_a_bags_load_time_warnings_at_its_first_message(tmp_path: Path) -> None:
    bag = _bag(tmp_path / "bag")
    first = _first_receive_time(bag)
    assert first == T0 + S  # by hand
    out = tmp_path / "robot.rrd"
    args = ["--bag", str(bag), "--urdf", str(_urdf(tmp_path)), "--inertia", "--rviz", str(RVIZ)]
    recording, _ = _record(out, *args)
    _assert_at_first_time(recording, out, first, LOADED)
    out = tmp_path / "no_robot.rrd"
    recording, stderr = _record(out, "--bag", str(bag), "--rviz", str(RVIZ))
    assert NO_ROBOT in stderr
    _assert_at_first_time(recording, out, first, (NO_ROBOT, RVIZ_NOTE))


def _live(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, urdf: Path | None) -> tuple[Path, int]:
    """A live run on a stand-in graph (no DDS) whose /joint_states were sent two seconds ago."""
    monkeypatch.setattr(live_run, "SETTLE_SECONDS", 0.1)
    graph = FakeGraph()
    graph.pubs = [Publication("/joint_states", JS, False, False)]
    sent_ns = time.time_ns() - 2 * S
    graph.queue = [Sample("/joint_states", JS, sent_ns + k, _js(["swivel"], [0.1 * k])) for k in range(3)]
    out = tmp_path / "live.rrd"
    config: Any = Config(urdf, SinkConfig(save=out), rviz=RVIZ, show=frozenset({"inertia"}))
    live_run.run_on(config, graph, threading.Event())
    return out, sent_ns


def test_a_live_graphs_load_time_warnings_at_its_first_message(tmp_path: Path, monkeypatch) -> None:
    out, sent_ns = _live(tmp_path, monkeypatch, _urdf(tmp_path))
    _assert_at_first_time(read_recording(out), out, sent_ns, LOADED)


def test_a_live_graph_without_a_robot_says_so_at_its_first_message(tmp_path: Path, monkeypatch) -> None:
    out, sent_ns = _live(tmp_path, monkeypatch, None)
    _assert_at_first_time(read_recording(out), out, sent_ns, (NO_ROBOT, RVIZ_NOTE))


def test_a_live_graphs_later_note_at_the_time_it_came(tmp_path: Path, monkeypatch) -> None:
    """A /robot_description that does not parse, sent a minute after the run started (a node started later): its
    line is a row at the source timestamp of the message that brought it, not at the run's start."""
    monkeypatch.setattr(live_run, "SETTLE_SECONDS", 0.1)

    graph = LateGraph()
    store = typestore("jazzy")
    text = bytes(store.serialize_cdr(store.types[STRING](data="<robot name='r'><link/></robot>"), STRING))
    graph.pubs = [Publication("/robot_description", STRING, True, True)]
    sent_ns = time.time_ns() + 60 * S
    graph.queue = [Sample("/robot_description", STRING, sent_ns, text)]
    out = tmp_path / "live.rrd"
    config: Any = Config(None, SinkConfig(save=out), duration=0.5)
    live_run.run_on(config, graph, threading.Event())
    rows = read_recording(out)["/warnings"]
    texts = [text[0] for text in rows.temporal["TextLog:text"]]
    [late] = [t for t, text in zip(rows.times, texts, strict=True) if "(showing transforms only)" in text]
    [start] = [t for t, text in zip(rows.times, texts, strict=True) if NO_ROBOT in text]
    assert late == sent_ns and start < sent_ns and not rows.static
