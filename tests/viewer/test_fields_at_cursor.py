"""Issue 37's findings on the generic fields and ``--plot``, written the way they were found: bags written by rosbags
(its serializer and writer), the CLI in a subprocess, the recording read back with Rerun's reader (tests/rrd.py),
every golden value from rosbags' deserializer of the same bytes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import cli
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from rrd import Rows, read_recording

TS = get_typestore(Stores.ROS2_HUMBLE)
T = TS.types
T0 = 1_700_000_000_000_000_000


def _write(path: Path, msgs: list[tuple[str, str, int, Any]]) -> tuple[Path, list[tuple[str, int, bytes]]]:
    """A rosbag2 MCAP of ``(topic, type, receive ns, rosbags message)``; also the bytes written."""
    written = []
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections: dict[str, Any] = {}
        for topic, msgtype, t, msg in msgs:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TS)
            data = bytes(TS.serialize_cdr(msg, msgtype))
            writer.write(connections[topic], t, data)
            written.append((topic, t, data))
    return path, written


def _header(ns: int, frame: str = "base_link") -> Any:
    return T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(ns, 1_000_000_000)), frame)


def _series(recording: dict[str, Rows], view: int, text: str) -> Rows:
    """The series of the ``--plot`` path ``text`` (the one named so)."""
    [rows] = [
        r for e, r in recording.items() if e.startswith(f"/plot/{view}/") and r.static["SeriesLines:names"] == [[text]]
    ]
    return rows


def _latest_at(rows: Rows, name: str, time_ns: int) -> Any:
    """What Rerun's latest-at shows for one component at ``time_ns``: its last row at or before it (None: never)."""
    found = None
    for t, value in zip(rows.times, rows.temporal.get(name, []), strict=False):
        if t <= time_ns and value is not None:
            found = value
    return found


def _scan(k: int) -> Any:
    ranges = (np.arange(360, dtype=np.float32) * 0.01 + k).astype(np.float32)
    return T["sensor_msgs/msg/LaserScan"](_header(T0 + k), -3.14, 3.14, 0.0174, 0.0, 0.1, 0.1, 30.0, ranges, ranges)


def test_an_item_of_a_summarised_array_is_plotted(tmp_path: Path) -> None:
    """`--plot /scan.ranges[180]` (360 rays), `/bumpers.data[1]` (bytes), `/people.poses[80].position.x` (100 poses)
    and `ranges[-1]` (Foxglove's last item) plotted nothing: the summary never produced the item."""
    msgs: list[tuple[str, str, int, Any]] = []
    for k in range(5):
        t = T0 + k * 100_000_000
        msgs.append(("/scan", "sensor_msgs/msg/LaserScan", t, _scan(k)))
        layout = T["std_msgs/msg/MultiArrayLayout"]([], 0)
        data = np.array([k, 10 + k, 200 + k], dtype=np.uint8)
        msgs.append(
            ("/bumpers", "std_msgs/msg/UInt8MultiArray", t + 1, T["std_msgs/msg/UInt8MultiArray"](layout, data))
        )
        poses = [
            T["geometry_msgs/msg/Pose"](
                T["geometry_msgs/msg/Point"](i + 0.5 * k, 0.0, 0.0),
                T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0),
            )
            for i in range(100)
        ]
        msgs.append(
            ("/people", "geometry_msgs/msg/PoseArray", t + 2, T["geometry_msgs/msg/PoseArray"](_header(t), poses))
        )
    bag, written = _write(tmp_path / "bag", msgs)
    paths = ["/scan.ranges[180]", "/scan.ranges[-1]", "/bumpers.data[1]", "/people.poses[80].position.x"]
    paths.append("/bumpers.data[:]")  # Foxglove's slice: every item
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), "--plot", *paths, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    golden = {
        "/scan.ranges[180]": lambda m: m.ranges[180],
        "/scan.ranges[-1]": lambda m: m.ranges[-1],
        "/bumpers.data[1]": lambda m: m.data[1],
        "/people.poses[80].position.x": lambda m: m.poses[80].position.x,
    }
    types = {t: m for t, m, _, _ in msgs}
    for text, read in golden.items():
        topic = text.split(".")[0]
        want = [(t, float(read(TS.deserialize_cdr(d, types[topic])))) for top, t, d in written if top == topic]
        rows = _series(recording, 0, text)
        assert rows.times == [t for t, _ in want], text
        assert [v[0] for v in rows.temporal["Scalars:scalars"]] == pytest.approx([v for _, v in want]), text
    rows = _series(recording, 0, "/bumpers.data[:]")
    want_all = [TS.deserialize_cdr(d, types["/bumpers"]).data.tolist() for top, _, d in written if top == "/bumpers"]
    assert rows.temporal["Scalars:scalars"] == want_all
    assert "no message of" not in result.stderr, result.stderr
    bumpers = recording["/topics/bumpers"]  # the topic's own fields: the summary, not the plotted item
    assert not any("data[1]" in name for name in bumpers.temporal), sorted(bumpers.temporal)
    assert any(name.endswith(":data.len") for name in bumpers.temporal)


def test_a_field_a_message_lacks_is_cleared_not_inherited(tmp_path: Path) -> None:
    """A trajectory of 5 points then one of 2: at the second's time the topic showed the first's points[2..4]."""
    traj, point = "trajectory_msgs/msg/JointTrajectory", T["trajectory_msgs/msg/JointTrajectoryPoint"]
    duration = T["builtin_interfaces/msg/Duration"](0, 0)

    def trajectory(n: int, k: int) -> Any:
        pts = [point(np.array([k + 0.1 * i]), np.zeros(0), np.zeros(0), np.zeros(0), duration) for i in range(n)]
        return T[traj](_header(T0), ["j1"], pts)

    msgs = [("/plan", traj, T0 + 10**9 * k, trajectory(n, k)) for k, n in enumerate((5, 2, 3))]
    bag, written = _write(tmp_path / "bag", msgs)
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    rows = read_recording(out)["/topics/plan"]
    names = {n.split(":", 1)[1]: n for n in rows.temporal if n.startswith(traj + ":")}
    for _, t, data in written:
        msg = TS.deserialize_cdr(data, traj)
        want = {f"points[{i}].positions[0]": p.positions[0] for i, p in enumerate(msg.points)}
        for field in (f"points[{i}].positions[0]" for i in range(5)):
            shown = _latest_at(rows, names[field], t)
            if field in want:
                assert shown == [pytest.approx(want[field])], (t, field)
            else:
                assert not shown, (t - T0, field, shown)  # cleared: nothing from an older message


def test_header_time_moves_the_plots_and_fields_with_unset_stamps_at_receive_time(tmp_path: Path) -> None:
    """`--time header` moved the drawings, not `--plot /odom.twist.twist.linear.x` nor the generic rows; an unset (0)
    stamp must fall back to the receive time, as for display topics."""
    msgs = []
    for k in range(4):
        stamp = 0 if k == 2 else 5_000_000_000 + k * 1_000_000  # sim time, far from receive time; one unset
        twist = T["geometry_msgs/msg/Twist"](
            T["geometry_msgs/msg/Vector3"](0.5 + k, 0, 0), T["geometry_msgs/msg/Vector3"](0, 0, 0)
        )
        pose = T["geometry_msgs/msg/Pose"](
            T["geometry_msgs/msg/Point"](0, 0, 0), T["geometry_msgs/msg/Quaternion"](0, 0, 0, 1)
        )
        odom = T["nav_msgs/msg/Odometry"](
            _header(stamp, "odom"),
            "base_link",
            T["geometry_msgs/msg/PoseWithCovariance"](pose, np.zeros(36)),
            T["geometry_msgs/msg/TwistWithCovariance"](twist, np.zeros(36)),
        )
        accel = T["geometry_msgs/msg/Vector3Stamped"](_header(stamp, "odom"), twist.linear)  # no display: fields
        msgs.append(("/odom", "nav_msgs/msg/Odometry", T0 + k * 10**8, odom))
        msgs.append(("/accel", "geometry_msgs/msg/Vector3Stamped", T0 + k * 10**8 + 1, accel))
    bag, written = _write(tmp_path / "bag", msgs)
    out = tmp_path / "out.rrd"
    result = cli(
        "--bag", str(bag), "--save", str(out), "--time", "header", "--plot", "/odom.twist.twist.linear.x", cwd=tmp_path
    )
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)

    def when(topic: str, msgtype: str) -> list[int]:
        out = []
        for top, t, data in written:
            if top == topic:
                s = TS.deserialize_cdr(data, msgtype).header.stamp
                out.append(s.sec * 10**9 + s.nanosec or t)
        return sorted(out)

    assert _series(recording, 0, "/odom.twist.twist.linear.x").times == when("/odom", "nav_msgs/msg/Odometry")
    assert recording["/topics/accel"].times == when("/accel", "geometry_msgs/msg/Vector3Stamped")


def test_joint_states_without_a_robot_are_a_topic_like_any_other(tmp_path: Path) -> None:
    """A joint-states bag without a robot recorded nothing for /joint_states (the Gazebo Panda bag)."""
    msgs = [
        (
            "/joint_states",
            "sensor_msgs/msg/JointState",
            T0 + k * 10**8,
            T["sensor_msgs/msg/JointState"](
                _header(T0 + k * 10**8), ["a", "b"], np.array([0.1 * k, -0.2 * k]), np.zeros(0), np.zeros(0)
            ),
        )
        for k in range(10)
    ]
    bag, written = _write(tmp_path / "bag", msgs)
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), "--plot", "/joint_states.position[1]", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    want = [(t, TS.deserialize_cdr(d, "sensor_msgs/msg/JointState")) for _, t, d in written]
    rows = recording["/topics/joint_states"]
    assert rows.times == [t for t, _ in want]
    assert [v[0] for v in rows.temporal["sensor_msgs/msg/JointState:name[0]"]] == ["a"] * 10
    assert [v[0] for v in rows.temporal["sensor_msgs/msg/JointState:position[0]"]] == pytest.approx(
        [m.position[0] for _, m in want]
    )
    series = _series(recording, 0, "/joint_states.position[1]")
    assert [v[0] for v in series.temporal["Scalars:scalars"]] == pytest.approx([m.position[1] for _, m in want])


def test_a_filter_on_the_topic_plots_only_the_messages_it_passes(tmp_path: Path) -> None:
    """Foxglove's `/topic{field==value}.x` was refused as a bad topic name."""
    msgs = []
    for k in range(6):
        twist = T["geometry_msgs/msg/Twist"](
            T["geometry_msgs/msg/Vector3"](k, 0, 0), T["geometry_msgs/msg/Vector3"](0, 0, 0)
        )
        msg = T["geometry_msgs/msg/TwistStamped"](_header(T0, "left" if k % 2 else "right"), twist)
        msgs.append(("/cmd", "geometry_msgs/msg/TwistStamped", T0 + k * 10**8, msg))
    bag, written = _write(tmp_path / "bag", msgs)
    out = tmp_path / "out.rrd"
    paths = ['/cmd{header.frame_id=="left"}.twist.linear.x', "/cmd{twist.linear.x>=3}.twist.linear.x"]
    result = cli("--bag", str(bag), "--save", str(out), "--plot", *paths, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    decoded = [(t, TS.deserialize_cdr(d, "geometry_msgs/msg/TwistStamped")) for _, t, d in written]
    for text, passes in zip(
        paths, (lambda m: m.header.frame_id == "left", lambda m: m.twist.linear.x >= 3), strict=True
    ):
        rows = _series(recording, 0, text)
        want = [(t, m.twist.linear.x) for t, m in decoded if passes(m)]
        assert rows.times == [t for t, _ in want], text
        assert [v[0] for v in rows.temporal["Scalars:scalars"]] == [v for _, v in want], text


@pytest.mark.parametrize(
    ("path", "named"),
    [
        ("/js.position[01]", "leading zero"),
        ("/js.position[1:3]", "slice with bounds"),
        ("/js.name[:]", "not an array of numbers"),
        ("/js.position[0]{x==1}", "filter inside"),
    ],
)
def test_a_refused_form_is_one_line_naming_it(tmp_path: Path, path: str, named: str) -> None:
    msgs = [
        (
            "/js",
            "sensor_msgs/msg/JointState",
            T0,
            T["sensor_msgs/msg/JointState"](_header(T0), ["a"], np.array([1.0]), np.zeros(0), np.zeros(0)),
        )
    ]
    bag, _ = _write(tmp_path / "bag", msgs)
    result = cli("--bag", str(bag), "--save", str(tmp_path / "out.rrd"), "--plot", path, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    assert named in result.stderr and "Traceback" not in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr


def test_a_real_bags_parameter_events_show_each_event_and_nothing_older(tmp_path: Path) -> None:
    """The e-puck bag's /parameter_events (91): 63 showed fields of earlier events at their time. Golden: rosbags'
    reader and deserializer, expanded to ``ros2 topic echo``'s names by tests/fieldbags.py."""
    from fieldbags import expected_fields
    from rosbags.highlevel import AnyReader

    repo = Path(__file__).resolve().parents[2]
    bag = repo.parent / "shared" / "bags" / "real" / "webots_epuck"
    if not bag.is_dir():
        pytest.skip("the real Webots e-puck bag (third-party data, not in this repository) is not here")
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), "--topics", "/parameter_events", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    rows = read_recording(out)["/topics/parameter_events"]
    msgtype = "rcl_interfaces/msg/ParameterEvent"
    with AnyReader([bag], default_typestore=TS) as reader:
        chosen = [c for c in reader.connections if c.topic == "/parameter_events"]
        events = [(t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages(chosen)]
    assert len(events) == 91
    for t, msg in events:
        want = expected_fields(TS, msg, msgtype)
        shown = {}
        for column in (c for c in rows.temporal if c.startswith(msgtype + ":")):
            if value := _latest_at(rows, column, t):
                shown[column.split(":", 1)[1]] = value[0]
        empty = {n[: -len(".len")] for n, v in want.items() if n.endswith(".len") and v == 0}
        shown = {n: v for n, v in shown.items() if not (n[:-4] in empty and n[-4:] in (".min", ".max"))}
        assert set(shown) == set(want), (t, set(shown) ^ set(want))
        for name, value in want.items():
            same = shown[name] == value or (isinstance(value, float) and np.isnan(value) and np.isnan(shown[name]))
            assert same, (t, name, shown[name], value)
