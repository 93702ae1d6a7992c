"""``r2d2-viz --ros`` against real Jazzy and Kilted rclpy nodes publishing the panda of example-robot-data, started
before us (late joiners): link poses in the recording against yourdfpy's FK of the published values, the share
of messages received, ``--save out.mcap`` read back by rosbags, ``--list``; malformed samples published as raw
bytes by the real node and a wrong type on /joint_states from a cyclonedds peer — the run survives, says each kind
once, and the good messages still land. Plus the CLI's refusals (no DDS needed)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yourdfpy
from conftest import cli, example_robots
from rrd import blueprint_components, blueprint_count, frame_edges_at, pose_in, read_recording, tf_by_child
from sources.live import ros_node
from sources.live.nodes.publish_robot import joint_names, joint_state_values

from r2d2_viz.cli import main
from r2d2_viz.msgs.typestore import typestore

PANDA = example_robots() / "panda_description" / "urdf" / "panda.urdf"
COUNT, RATE = 300, 100


def _scenario(
    distro: str, runs: list[list[str]], *, node: list[str] = (), wrong_type: bool = False, server: Path | None = None
) -> Any:
    python = ros_node.require_live(distro)
    script = Path(ros_node.__file__).with_name("cli_scenario.py")
    exe = Path(sys.executable).parent / "r2d2-viz"
    command = [
        sys.executable,
        str(script),
        "--ros-python",
        str(python),
        "--urdf",
        str(PANDA),
        "--cli",
        str(exe),
        "--runs",
        json.dumps(runs),
        "--node",
        json.dumps([*node, "--rate", str(RATE), "--count", str(COUNT)]),
    ]
    if wrong_type:
        command.append("--wrong-type-peer")
    if server is not None:  # a rerun gRPC server in the namespace, for --connect runs (port 9877)
        command += ["--rerun", str(Path(sys.executable).parent / "rerun"), "--server-save", str(server)]
    done = ros_node.in_netns(command, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def _received(stderr: str) -> dict[str, int]:
    line = next(x for x in stderr.splitlines() if x.startswith("r2d2-viz: received "))
    return {t: int(n) for t, n in (p.rsplit(" ", 1) for p in line.removeprefix("r2d2-viz: received ").split(", "))}


def _check_poses(path: Path, *, header_time: bool) -> int:
    """Link poses at a few of the recorded joint states against yourdfpy (Rerun keeps float32: 2e-6); returns
    the joint states recorded."""
    recording = read_recording(path)
    names = joint_names(PANDA.read_text(), 0)
    times = sorted(set(tf_by_child(recording)["panda_link1"].times))
    urdf = yourdfpy.URDF.load(str(PANDA), load_meshes=False, load_collision_meshes=False)
    good = [t for t in times if t >= 1000 * 10**9] if header_time else times[-COUNT:]
    for i in np.linspace(0, len(good) - 1, 6).astype(int):
        t = good[i]
        k = (t - 1000 * 10**9) // 1_000_000 if header_time else i + COUNT - len(good)
        _, _, position, _ = joint_state_values(int(k), len(names))
        urdf.update_cfg({n: v for n, v in zip(names, position, strict=True) if n in urdf.actuated_joint_names})
        edges = frame_edges_at(recording, t)
        for link in ("panda_link3", "panda_link7", "panda_hand", "panda_leftfinger"):
            theirs = urdf.get_transform(frame_to=link, frame_from="panda_link0")
            np.testing.assert_allclose(pose_in(edges, link, "panda_link0"), theirs, atol=2e-6, err_msg=f"{link} k={k}")
    return len(good)


@pytest.mark.slow
def test_jazzy_node_recorded_bagged_and_malformed_samples_survived(tmp_path: Path) -> None:
    rrd, bag = tmp_path / "out.rrd", tmp_path / "out.mcap"
    # each run: a Ctrl-C once the node has sent everything (cli_scenario.py); --duration only bounds it
    runs = [["--save", str(rrd), "--duration", "30", "--time", "header"], ["--save", str(bag), "--duration", "30"]]
    # --log: the node also logs a line at each level (one real node for both; was a scenario of its own)
    result = _scenario("jazzy", runs, node=["--bad", "--log"], wrong_type=True)
    assert result["list_rc"] == 0
    assert "/joint_states [sensor_msgs/msg/JointState] 1 publisher" in result["list"]
    assert "/joint_states [std_msgs/msg/String] 1 publisher" in result["list"]
    assert "/robot_description [std_msgs/msg/String] 1 publisher" in result["list"]
    assert result["node"]["matched"] and result["node"]["sent"] == COUNT
    for run in result["runs"]:
        assert run["rc"] == 0, run["stderr"][-3000:]
        err = run["stderr"]
        assert err.count("/joint_states: a publisher of std_msgs/msg/String, not sensor_msgs/msg/JointState") == 1
        assert err.count("name and position lengths differ") == 2  # said when first seen, counted at the end
        assert err.count("NaN or infinite positions") == 2
        assert err.count("ignored joints the robot does not have") == 1  # the 10,000 names: one line
        assert _received(err)["/joint_states"] >= 0.995 * COUNT + 3  # + the three valid malformed ones
        assert _received(err)["/robot_description"] == 1
    assert _check_poses(rrd, header_time=True) >= 0.995 * COUNT
    _check_log(rrd)
    from rosbags.highlevel import AnyReader

    store = typestore("jazzy")
    with AnyReader([bag], default_typestore=store) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types == {
            "/joint_states": "sensor_msgs/msg/JointState",
            "/robot_description": "std_msgs/msg/String",
            "/rosout": "rcl_interfaces/msg/Log",
        }
        states = [(c, raw) for c, _, raw in reader.messages() if c.topic == "/joint_states"]
        description = [raw for c, _, raw in reader.messages() if c.topic == "/robot_description"]
    assert store.deserialize_cdr(description[0], "std_msgs/msg/String").data == PANDA.read_text()
    names = joint_names(PANDA.read_text(), 0)
    same = undecodable = 0
    for _, raw in states:
        try:
            msg = store.deserialize_cdr(raw, "sensor_msgs/msg/JointState")
        except Exception:
            undecodable += 1  # a malformed sample, recorded as it came (as ros2 bag record would)
            continue
        if msg.header.stamp.sec < 1000:
            continue
        k = (msg.header.stamp.sec - 1000) * 1000 + msg.header.stamp.nanosec // 1_000_000
        sec, nanosec, position, velocity = joint_state_values(k, len(names))
        expected = store.types["sensor_msgs/msg/JointState"](
            header=store.types["std_msgs/msg/Header"](
                stamp=store.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec), frame_id="base"
            ),
            name=names,
            position=np.array(position),
            velocity=np.array(velocity),
            effort=np.zeros(0),
        )
        ours = bytes(store.serialize_cdr(expected, "sensor_msgs/msg/JointState"))
        # rclpy's bytes, as they came: equal to rosbags' but for alignment padding, which rclpy leaves unzeroed
        padding = [i for i in range(len(ours)) if raw[i] != ours[i]]
        same += int(len(raw) == len(ours) and all(ours[i] == 0 for i in padding) and len(padding) <= 12)
    assert same >= 0.995 * COUNT
    assert undecodable <= len(["bad CDR", "absurd length", "NaN", "lengths differ", "10,000 names"])


@pytest.mark.slow
def test_kilted_node_recorded_at_source_timestamps_and_streamed_to_a_viewer(tmp_path: Path) -> None:
    rrd, received = tmp_path / "out.rrd", tmp_path / "received.rrd"
    runs = [
        ["--save", str(rrd), "--duration", "30"],
        ["--connect", "rerun+http://127.0.0.1:9877/proxy", "--duration", "30"],
    ]
    result = _scenario("kilted", runs, server=received)
    assert "/joint_states [sensor_msgs/msg/JointState] 1 publisher" in result["list"]
    for run in result["runs"]:
        assert run["rc"] == 0, run["stderr"][-3000:]
        assert _received(run["stderr"])["/joint_states"] >= 0.995 * COUNT
    assert _check_poses(rrd, header_time=False) >= 0.995 * COUNT
    # --connect: a running viewer (Rerun's gRPC server, which saved what it got) shows the same robot moving
    assert result["server_rc"] in (0, 130)  # interrupted, as a user closes it: it saves on the way out
    assert _check_poses(received, header_time=False) >= 0.995 * COUNT


def _check_log(rrd: Path) -> None:
    """The real Jazzy node's log, a line at each level: /rosout (rcl_interfaces/msg/Log, which every node publishes)
    is read like a bag's, each line a TextLog with its level and rqt_console's text, in a log view."""
    from sources.live.nodes.publish_robot import LOG_LINES

    rows = read_recording(rrd)["/rosout"]
    lines = [
        (level[0], text[0])
        for level, text in zip(rows.temporal["TextLog:level"], rows.temporal["TextLog:text"], strict=True)
        if text is not None
    ]
    assert [level for level, _ in lines] == [level for level, _ in LOG_LINES]
    for (level, text), (_, method) in zip(lines, LOG_LINES, strict=True):
        assert text.startswith(f"[r2d2_viz_test_robot] {level} line (") and "publish_robot.py:main:" in text, method
    # the log view: planned with the view when /rosout was there in time, else sent when it appeared
    stores = [blueprint_components(rrd, which=k) for k in range(blueprint_count(rrd))]
    assert any(["Log: /rosout"] in [c.get("ViewBlueprint:display_name") for c in s.values()] for s in stores)


def test_list_needs_ros_and_ros_refuses_a_bag(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--list"]) == 2
    assert main(["--ros", "--bag", "x.mcap"]) == 2
    err = capsys.readouterr().err
    assert "use it with --ros or --bag PATH" in err and "cannot be combined with --bag" in err


def test_missing_cyclonedds_is_one_line_exit_2(without_cyclonedds: None, capsys: Any) -> None:
    assert main(["--ros", "--list"]) == 2
    assert main(["--ros", "--save", "x.rrd", "--duration", "1"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and all("pip install 'cyclonedds" in line for line in lines)


def test_help_names_ros() -> None:
    done = cli("--help")
    assert done.returncode == 0 and "--ros" in done.stdout and "--list" in done.stdout


def test_a_description_that_does_not_parse_then_one_that_does(
    tmp_path: Path, capsys: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No DDS: a stand-in graph hands over a broken /robot_description, then a good one, then joint states. The
    run says the first once and goes on with transforms only, then loads the robot and moves it."""
    import threading

    from sources.live.test_source import JS, FakeGraph, _js
    from test_live_run_stand_in import URDF, Config

    import r2d2_viz.live_run as live_run
    from r2d2_viz.sources.live.dds import Publication, Sample
    from r2d2_viz.viewer.sinks import SinkConfig

    store = typestore("jazzy")

    def description(text: str) -> bytes:
        msg = store.types["std_msgs/msg/String"](data=text)
        return bytes(store.serialize_cdr(msg, "std_msgs/msg/String"))

    class Stepwise(FakeGraph):  # one list of samples per poll
        def __init__(self, steps: list[list[Sample]]) -> None:
            super().__init__()
            self.steps = steps

        def poll(self) -> list[Sample]:
            return self.steps.pop(0) if self.steps else []

    t = 1_700_000_000_000_000_000
    string = "std_msgs/msg/String"
    monkeypatch.setattr(live_run, "SETTLE_SECONDS", 0.1)
    broken = [Sample("/robot_description", string, t, description("<robot name='broken'><link"))]
    good = [Sample("/robot_description", string, t + 1, description(URDF))]
    joints = [Sample("/joint_states", JS, t + 2 + k, _js(["j"], [0.1 * k])) for k in range(3)]
    graph = Stepwise([broken, *[[]] * 10, good, [], [], joints])  # the broken one within the settle, then a pause
    graph.pubs = [Publication("/robot_description", string, True, True), Publication("/joint_states", JS, False, False)]
    config = Config(None, SinkConfig(save=tmp_path / "out.rrd"), duration=1.0)
    samples, _, _ = live_run.run_on(config, graph, threading.Event())  # type: ignore[arg-type]
    err = capsys.readouterr().err
    assert err.count("(showing transforms only)") == 1
    assert "/robot_description changed: robot 'one' reloaded" in err
    assert samples == 3, err
    recording = read_recording(tmp_path / "out.rrd")
    assert len(recording["/joints/limited"].times) == 3  # the reloaded robot's joint moved


def test_a_log_that_appears_after_the_view_was_planned_gets_its_view(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No DDS: a stand-in graph offers /rosout only after the settle (a node started after the viewer, as RViz
    users do). Its lines are logged, and a layout with its log view is sent when it appears: the recording's last
    blueprint has the view, its first (planned before) has none."""
    import threading

    from sources.live.test_source import FakeGraph
    from test_live_run_stand_in import Config

    import r2d2_viz.live_run as live_run
    from r2d2_viz.sources.live.dds import Publication, Sample
    from r2d2_viz.viewer.sinks import SinkConfig

    store = typestore("jazzy")
    log = "rcl_interfaces/msg/Log"
    t = 1_700_000_000_000_000_000

    def line(k: int) -> bytes:
        stamp = store.types["builtin_interfaces/msg/Time"](sec=1_700_000_000, nanosec=k)
        msg = store.types[log](stamp=stamp, level=30, name="late_node", msg=f"line {k}", file="f.py", function="g",
                               line=k)  # fmt: skip
        return bytes(store.serialize_cdr(msg, log))

    class Late(FakeGraph):  # nothing while the view is planned, then /rosout
        def __init__(self) -> None:
            super().__init__()
            self.polls = 0

        def poll(self) -> list[Sample]:
            self.polls += 1
            if self.polls == 20:
                self.pubs = [Publication("/rosout", log, True, True)]
            return [Sample("/rosout", log, t + self.polls, line(self.polls))] if 25 <= self.polls < 28 else []

    monkeypatch.setattr(live_run, "SETTLE_SECONDS", 0.1)
    out = tmp_path / "late.rrd"
    config = Config(None, SinkConfig(save=out), duration=2.0)
    live_run.run_on(config, Late(), threading.Event())  # type: ignore[arg-type]
    rows = read_recording(out)["/rosout"]
    assert [text[0] for text in rows.temporal["TextLog:text"] if text is not None] == [
        f"[late_node] line {k} (f.py:g:{k})" for k in (25, 26, 27)
    ]

    # two layouts: the one planned (no log view) and the one sent when /rosout appeared (the reader's order is not
    # the order they were sent in)
    logs = [
        ["Log: /rosout"] in [c.get("ViewBlueprint:display_name") for c in blueprint_components(out, which=k).values()]
        for k in range(blueprint_count(out))
    ]
    assert sorted(logs) == [False, True], logs


def test_an_empty_graph_says_what_was_searched_and_how_to_check(tmp_path: Path) -> None:
    """In a network namespace with only loopback nothing publishes: ``--ros --list`` and ``--ros --save`` used to
    print nothing or only 'received nothing'; now they name the domain, how long, the discovery range and how to
    check (ROS_DOMAIN_ID 42 and LOCALHOST set here, so the line must carry what the environment says)."""
    missing = ros_node.netns_missing()
    if missing:
        pytest.skip(missing)
    exe = str(Path(sys.executable).parent / "r2d2-viz")
    env = {"ROS_DOMAIN_ID": "42", "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    listed = ros_node.in_netns([exe, "--ros", "--list"], timeout=120, env=env)
    assert listed.returncode == 0 and listed.stdout == "", listed.stderr
    searched, hint = listed.stderr.strip().splitlines()
    domain = "ROS_DOMAIN_ID 42, discovery range LOCALHOST (this machine only)"
    assert searched == f"r2d2-viz: no topics after 5 s of discovery on {domain}"  # 5 s: nodes' names (NODE_SECONDS)
    assert hint.startswith("r2d2-viz: check that") and "ros2 topic list" in hint and "ROS_STATIC_PEERS" in hint
    # the next step is one worth taking: not the command just run, but the one that keeps waiting
    assert "--ros --list" not in hint and hint.endswith("; r2d2-viz --ros keeps waiting for publishers"), hint
    out = tmp_path / "x.rrd"
    saved = ros_node.in_netns([exe, "--ros", "--save", str(out), "--duration", "2"], timeout=120, env=env)
    assert saved.returncode == 0, saved.stderr
    lines = saved.stderr.splitlines()
    [k] = [i for i, x in enumerate(lines) if x.startswith("r2d2-viz: received ")]
    assert lines[k].startswith("r2d2-viz: received nothing in "), saved.stderr
    assert lines[k].endswith(" s on ROS_DOMAIN_ID 42, discovery range LOCALHOST (this machine only)"), lines[k]
    assert lines[k + 1].startswith("r2d2-viz: check that"), saved.stderr
    assert lines[k + 1].endswith("; r2d2-viz --ros --list lists what this machine sees"), lines[k + 1]
    assert all(len(x) <= 300 for x in lines + listed.stderr.splitlines())
    assert out.exists()
