"""The robot's log, its diagnostics and the sensors no RViz display draws, through the real CLI from bags rosbags
wrote (ROS 2 MCAP and ROS 1), read back with Rerun's reader: TextLog lines with their levels, a state per
diagnostic status with its key/values, plots, a map point, and the views the layout gains for them. Expected values
are worked out by hand in tests/telemetrybags.py; the ROS 1 bag's statuses also as rosbags' own ROS 1 reader reads
them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from rosbags.rosbag1 import Reader as Ros1Reader
from rrd import blueprint_components, read_recording
from telemetrybags import (
    BATTERY,
    BATTERY_TIME,
    DIAG,
    DIAG_ENTITIES,
    DIAG_STATES,
    FIX,
    FIX_TIME,
    FLAG,
    IMU_ACCEL,
    IMU_AXES,
    IMU_RATES,
    IMU_TIME,
    LOG,
    NOETIC,
    NUMBERS,
    STRING,
    STRING_TIME,
    write_ros1_telemetry_bag,
    write_telemetry_bag,
)

from r2d2_viz.viewer.blocks.plain_log import STATE_COLORS


def _replay(tmp_path: Path, bag: Path) -> tuple[Path, str]:
    out = tmp_path / f"{bag.name}.rrd"
    result = cli("--bag", str(bag), "--save", str(out))
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    return out, result.stderr


def _rows(rows, column: str) -> list[tuple[int, object]]:
    """(time, value) of the rows where ``column`` was logged."""
    return [(t, v) for t, v in zip(rows.times, rows.temporal.get(column, []), strict=False) if v is not None]


def _check_log_and_diagnostics(recording: dict) -> None:
    rosout = recording["/rosout"]
    assert _rows(rosout, "TextLog:level") == [(t, [level]) for t, *_, level in LOG]
    texts = [f"[{node}] {text} ({f}:{fn}:{line})" for _, _, _, node, text, f, fn, line, _ in LOG]  # rqt_console's
    assert [v for _, v in _rows(rosout, "TextLog:text")] == [[t] for t in texts]
    for name, entity in DIAG_ENTITIES.items():
        rows = recording[entity]
        times = [t for t, statuses in DIAG if any(s[0] == name for s in statuses)]
        assert _rows(rows, "StateChange:state") == [(t, [s]) for t, s in zip(times, DIAG_STATES[name], strict=True)]
        # every state coloured as rqt_robot_monitor colours its level
        configured = rows.static["StateConfiguration:values"][-1]
        colors = rows.static["StateConfiguration:colors"][-1]
        assert configured == DIAG_STATES[name]
        assert colors == [STATE_COLORS[s.split(":")[0]] for s in configured]
    motor = recording[DIAG_ENTITIES["motor: left"]]
    current = [v[0] for _, v in _rows(motor, "DiagnosticStatus:current")]
    assert current[:2] == [1.5, 4.25] and math.isnan(current[2])  # a number field stays one ("n/a": a gap)
    assert [v for _, v in _rows(motor, "DiagnosticStatus:mode")] == [["auto"], ["auto"], ["off"]]
    assert [v for _, v in _rows(motor, "DiagnosticStatus:message")] == [["running"], ["hot"], ["stalled"]]
    assert [v for _, v in _rows(motor, "DiagnosticStatus:name")] == [["motor: left"]] * 3


def _check_imu_and_numbers(recording: dict) -> None:
    imu = recording["/imu"]
    [(t, vectors)] = _rows(imu, "Arrows3D:vectors")
    assert t == IMU_TIME
    np.testing.assert_allclose(vectors, IMU_AXES, atol=1e-6)  # 90° about z, by hand
    assert dict(_rows(imu, "CoordinateFrame:frame"))[IMU_TIME] == ["imu_link"]
    assert _rows(recording["/imu/angular_velocity"], "Scalars:scalars") == [(IMU_TIME, IMU_RATES)]
    assert recording["/imu/angular_velocity"].static["SeriesLines:names"][-1] == ["x", "y", "z"]
    [(_, accel)] = _rows(recording["/imu/linear_acceleration"], "Scalars:scalars")
    np.testing.assert_allclose(accel, IMU_ACCEL)
    assert _rows(recording["/speed"], "Scalars:scalars") == [(t, [v]) for t, v in NUMBERS]


@pytest.mark.parametrize("storage", ["mcap", "ros1"])
def test_the_log_and_diagnostics_land_with_their_levels_and_states(tmp_path: Path, storage: str) -> None:
    bag = (
        write_telemetry_bag(tmp_path / "tele")
        if storage == "mcap"
        else write_ros1_telemetry_bag(tmp_path / "tele.bag")  # rosgraph_msgs/Log: levels 1, 2, 4, 8, 16
    )
    out, stderr = _replay(tmp_path, bag)
    recording = read_recording(out)
    _check_log_and_diagnostics(recording)
    _check_imu_and_numbers(recording)
    assert "cannot be shown" not in stderr and "empty frame_id" not in stderr


def test_the_ros1_statuses_are_those_rosbags_reads(tmp_path: Path) -> None:
    bag = write_ros1_telemetry_bag(tmp_path / "tele.bag")
    expected: dict[str, list[str]] = {}
    levels = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}  # diagnostic_msgs/DiagnosticStatus's constants
    with Ros1Reader(bag) as reader:
        for c, _, raw in reader.messages([c for c in reader.connections if c.topic == "/diagnostics"]):
            for s in NOETIC.deserialize_ros1(raw, c.msgtype).status:
                expected.setdefault(s.name, []).append(levels[s.level] + (f": {s.message}" if s.message else ""))
    recording = read_recording(_replay(tmp_path, bag)[0])
    for name, states in expected.items():
        got = [v[0] for _, v in _rows(recording[DIAG_ENTITIES[name]], "StateChange:state")]
        assert got == states


def test_sensors_a_map_point_and_text(tmp_path: Path) -> None:
    out, _ = _replay(tmp_path, write_telemetry_bag(tmp_path / "tele"))
    recording = read_recording(out)
    assert _rows(recording["/fix"], "GeoPoints:positions") == [(FIX_TIME, [list(FIX[:2])])]
    assert _rows(recording["/fix/altitude"], "Scalars:scalars") == [(FIX_TIME, [FIX[2]])]
    for field, value in BATTERY.items():
        [(t, [got])] = _rows(recording[f"/battery/{field}"], "Scalars:scalars")
        assert t == BATTERY_TIME and got == pytest.approx(value)  # (percentage is a float32: 0.8 to 1e-7)
    assert _rows(recording["/flag"], "Scalars:scalars") == [(t, [float(v)]) for t, v in FLAG]
    assert _rows(recording["/status"], "TextLog:text") == [(STRING_TIME, [STRING])]


def _views(path: Path) -> dict[str, tuple[str, list[str]]]:
    """View name → (its kind, its contents) of the recording's blueprint."""
    parts = blueprint_components(path)
    out = {}
    for entity, components in parts.items():
        kind = components.get("ViewBlueprint:class_identifier")
        if kind and entity.count("/") == 2:
            contents = parts.get(f"{entity}/ViewContents", {}).get("ViewContents:query", [])
            out[components["ViewBlueprint:display_name"][0]] = (kind[0], contents)
    return out


def test_the_layout_gains_a_log_a_state_timeline_a_map_and_plots(tmp_path: Path) -> None:
    out, _ = _replay(tmp_path, write_telemetry_bag(tmp_path / "tele"))
    views = _views(out)
    assert views["Log: /rosout · /status"] == ("TextLog", ["+ /rosout/**", "+ /status/**"])
    assert views["Diagnostics: /diagnostics"] == ("StateTimeline", ["+ /diagnostics/**"])
    assert views["Map: /fix"] == ("Map", ["+ /fix/**"])
    for topic in ("/battery", "/fix", "/flag", "/imu", "/speed"):  # a plot each
        assert views[topic] == ("TimeSeries", ["$origin/**"])


def test_bad_strings_and_non_finite_values_are_said_once_per_topic(tmp_path: Path) -> None:
    """A /rosout line that is not UTF-8 (twice) and an Imu whose orientation is NaN: one line for the log topic,
    the other lines shown; the Imu's rates still plotted, without its axes."""
    from bagmaker import BagSpec, write_bag
    from telemetrybags import HUMBLE, T0, S

    T = HUMBLE.types
    good = T["rcl_interfaces/msg/Log"](T["builtin_interfaces/msg/Time"](1, 0), 20, "n", "fine", "f", "g", 1)
    raw = bytearray(HUMBLE.serialize_cdr(good, "rcl_interfaces/msg/Log"))
    at = bytes(raw).index(b"fine")
    raw[at : at + 4] = b"\xff\xfe\xfd\xfc"  # the same length: only the bytes are not UTF-8
    header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](1, 0), "imu_link")
    nan_q = T["geometry_msgs/msg/Quaternion"](math.nan, 0.0, 0.0, 1.0)
    v = T["geometry_msgs/msg/Vector3"](1.0, 2.0, 3.0)
    imu = T["sensor_msgs/msg/Imu"](header, nan_q, np.zeros(9), v, np.zeros(9), v, np.zeros(9))
    spec = BagSpec(types={"/rosout": "rcl_interfaces/msg/Log", "/imu": "sensor_msgs/msg/Imu"})
    spec.add("/rosout", T0, bytes(raw)).add("/rosout", T0 + S, bytes(raw))
    spec.add("/rosout", T0 + 2 * S, bytes(HUMBLE.serialize_cdr(good, "rcl_interfaces/msg/Log")))
    spec.add("/imu", T0 + S, bytes(HUMBLE.serialize_cdr(imu, "sensor_msgs/msg/Imu")))
    out, stderr = _replay(tmp_path, write_bag(tmp_path / "bad", spec))
    lines = stderr.splitlines()
    assert sum("/rosout: a rcl_interfaces/msg/Log message cannot be shown" in x for x in lines) == 1
    assert any("/rosout: 2 of 3 messages could not be shown" in x for x in lines)
    path_len = len(str(tmp_path / "bad"))  # each line names the bag; its folder (longer under xdist) aside
    assert max(len(x) - path_len for x in lines) <= 300, stderr
    recording = read_recording(out)
    assert [v for _, v in _rows(recording["/rosout"], "TextLog:text")] == [["[n] fine (f:g:1)"]]
    assert _rows(recording["/imu/angular_velocity"], "Scalars:scalars") == [(T0 + S, [1.0, 2.0, 3.0])]
    assert not _rows(recording["/imu"], "Arrows3D:vectors")


REAL_LOGS = {
    "ros1/example-lz4.bag": {1: "DEBUG", 2: "INFO", 4: "WARN", 8: "ERROR", 16: "CRITICAL"},  # rosgraph_msgs/Log
    "talker_mcap": {10: "DEBUG", 20: "INFO", 30: "WARN", 40: "ERROR", 50: "CRITICAL"},  # rcl_interfaces/msg/Log
}
"""Bags recorded by ROS 1's rosbag and ROS 2's ros2 bag (tests/data/bags), each with its /rosout, and their log
levels as Rerun names them (FATAL is Rerun's CRITICAL), by hand from the two message definitions."""


def _rosout(bag: Path) -> list[tuple[int, int, object]]:
    """(receive time, level, message) of each /rosout message, read by rosbags: its ROS 1 reader, or for the ROS 2
    talker (whose folder rosbags' directory reader yields nothing for: see tests/data/bags/README.md) the same
    messages in its sqlite3 twin, read with SQL and deserialised by rosbags with Humble's types."""
    import sqlite3

    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    humble = get_typestore(Stores.ROS2_HUMBLE)
    if bag.suffix == ".bag":
        with AnyReader([bag], default_typestore=humble) as reader:
            rows = reader.messages([c for c in reader.connections if c.topic == "/rosout"])
            return [(t, (m := reader.deserialize(raw, c.msgtype)).level, m) for c, t, raw in rows]
    db = bag.parent / "talker_db3" / "talker.db3"
    with sqlite3.connect(db) as con:
        query = "SELECT m.timestamp, m.data FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name = ?"
        rows = con.execute(query + " ORDER BY m.timestamp", ("/rosout",)).fetchall()
    return [(t, (m := humble.deserialize_cdr(data, "rcl_interfaces/msg/Log")).level, m) for t, data in rows]


@pytest.mark.parametrize("name", sorted(REAL_LOGS))
def test_a_real_bags_rosout_is_what_rosbags_reads(tmp_path: Path, name: str) -> None:
    from conftest import REPO

    bag = REPO / "tests" / "data" / "bags" / name
    expected = [
        (t, REAL_LOGS[name][level], f"[{m.name}] {m.msg} ({m.file}:{m.function}:{m.line})")  # type: ignore[attr-defined]
        for t, level, m in _rosout(bag)
    ]
    assert len(expected) == 10
    out = tmp_path / "real.rrd"
    result = cli("--bag", str(bag), "--save", str(out))
    assert result.returncode == 0, result.stderr
    rows = read_recording(out)["/rosout"]
    got = [(t, level[0], text[0]) for (t, level), (_, text) in
           zip(_rows(rows, "TextLog:level"), _rows(rows, "TextLog:text"), strict=True)]  # fmt: skip
    assert got == expected


def test_terminal_escapes_from_a_bag_never_reach_the_recordings_text(tmp_path: Path) -> None:
    """The log view of the e-puck bag's picture showed ``[94mLoaded [1mjoint_state_broadcaster[0m`` (issue 36):
    ros2_control's spawner writes terminal colours into /rosout (these very bytes are in
    ../shared/bags/real/webots_epuck). Through the CLI, a bag rosbags wrote with them, a title-setting escape in a
    std_msgs/String and colours in a diagnostic status: colours dropped, every other control character shown as
    ``\\x..``, no ESC byte in any text of the recording. Expected texts by hand."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from telemetrybags import HUMBLE, T0, _diagnostics, _tf, _time

    T = HUMBLE.types
    spawner = "\x1b[94mLoaded \x1b[1mjoint_state_broadcaster\x1b[0m"
    log = T["rcl_interfaces/msg/Log"](_time(HUMBLE, T0), 20, "spawner_jsb", spawner, "spawner.py", "main", 7)
    header = T["std_msgs/msg/Header"](_time(HUMBLE, T0), "")
    rows = {
        "/tf_static": ("tf2_msgs/msg/TFMessage", _tf(HUMBLE, T["std_msgs/msg/Header"](_time(HUMBLE, T0), "odom"))),
        "/rosout": ("rcl_interfaces/msg/Log", log),
        "/chatter": ("std_msgs/msg/String", T["std_msgs/msg/String"]("\x1b]0;pwned\x07ok\r\x9b2J")),
        "/diagnostics": (
            "diagnostic_msgs/msg/DiagnosticArray",
            _diagnostics(HUMBLE, header, [("motor", 1, "\x1b[33mhot\x1b[0m", [("mode", "\x1b[1mauto")])]),
        ),
    }
    bag = tmp_path / "escapes"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        for k, (topic, (typename, msg)) in enumerate(rows.items()):
            c = writer.add_connection(topic, typename, typestore=HUMBLE)
            writer.write(c, T0 + k, bytes(HUMBLE.serialize_cdr(msg, typename)))
    recording = read_recording(_replay(tmp_path, bag)[0])
    assert [v for _, v in _rows(recording["/rosout"], "TextLog:text")] == [
        ["[spawner_jsb] Loaded joint_state_broadcaster (spawner.py:main:7)"]
    ]
    assert [v for _, v in _rows(recording["/chatter"], "TextLog:text")] == [["\\x1b]0;pwned\\x07ok\\x0d\\x9b2J"]]
    assert [v for _, v in _rows(recording["/diagnostics/motor"], "StateChange:state")] == [["WARN: hot"]]

    def strings(value: object) -> list[str]:
        if isinstance(value, str):
            return [value]
        return [s for v in value for s in strings(v)] if isinstance(value, (list, tuple)) else []

    texts = [
        t
        for rows_ in recording.values()
        for c in (*rows_.temporal.values(), *rows_.static.values())
        for t in strings(c)
    ]
    assert "WARN: hot" in texts and not [t for t in texts if "\x1b" in t or "\x07" in t]
