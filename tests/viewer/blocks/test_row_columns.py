"""Every other display as columns (issue 46, item 3): IMU, log lines, diagnostics states, markers (with a delete, a
DELETEALL and a lifetime), paths, poses and pose arrays, fixes and numbers go out as ``send_columns`` runs, and the
recording read back is the one per-message logging made (entities, times, every component), batch and live.

The messages are built and serialised by rosbags (``tests/msgs_build.py``); the values checked come from rosbags'
own deserialisation of those bytes and numpy (the IMU's axes: the columns of the quaternion's rotation matrix by
hand, × 0.3 m), never from r2d2_viz."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import rerun as rr
from msgs_build import TS, T, cdr, color, duration, header, marker_msg, pose, quat, vec
from rrd import Rows, read_recording, rows_in_order

from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.viewer.blocks import row_columns
from r2d2_viz.viewer.blocks.row_columns import RowColumns
from r2d2_viz.viewer.display_feed import DisplayFeed
from r2d2_viz.viewer.displays import set_time
from r2d2_viz.viewer.notices import Notices

S = 1_000_000_000
T0 = 1_700_000_000 * S
IMU_Q = [(0.0, 0.0, np.sin(k / 10), np.cos(k / 10)) for k in range(6)]  # (x, y, z, w): k/5 rad about z


def _imu(k: int) -> bytes:
    v3 = T("geometry_msgs/msg/Vector3")
    z9 = np.zeros(9)
    q = quat(*IMU_Q[k])
    return cdr(T("sensor_msgs/msg/Imu")(header("imu_link"), q, z9, v3(0.1 * k, -0.2, 0.3), z9, v3(0, k, 9.81), z9))


def _log(k: int) -> bytes:
    stamp = T("builtin_interfaces/msg/Time")(sec=k, nanosec=0)
    return cdr(T("rcl_interfaces/msg/Log")(stamp, (10, 20, 30, 40)[k % 4], "node", f"line {k}", "a.cpp", "f", k))


def _diagnostics(k: int) -> bytes:
    kv, status = T("diagnostic_msgs/msg/KeyValue"), T("diagnostic_msgs/msg/DiagnosticStatus")
    items = [status(k % 3, f"motor {m}", "ok" if k % 2 else "hot", "hw", [kv("current", str(k))]) for m in range(2)]
    return cdr(T("diagnostic_msgs/msg/DiagnosticArray")(header(""), items))


def _markers(k: int) -> bytes:
    """Six markers a message; the 4th message deletes the sphere, the 6th draws it and clears namespace "b" (at
    one time: the clear comes after the drawing)."""
    cube = marker_msg(1, ns="a", id=1, pose=pose(k, 0, 0), scale=vec(0.5, 0.5, 0.5), color=color(0, 0, 1))
    line = marker_msg(4, ns="a", id=2, points=[vec(0, 0, 0, "Point"), vec(k, 1, 0, "Point")], scale=vec(0.1, 0, 0))
    sphere = marker_msg(2, ns="b", id=3, pose=pose(0, k, 0), lifetime=duration(0, 250_000_000))
    text = marker_msg(9, ns="b", id=4, text=f"t{k}", pose=pose(0, 0, k))
    cylinder = marker_msg(3, ns="c", id=5, pose=pose(k, k, 0), scale=vec(0.2, 0.2, 1.0))
    arrow = marker_msg(0, ns="c", id=6, pose=pose(0, 0, k), scale=vec(1.0, 0.1, 0.1), color=color(1, 0, 0, 0.5))
    markers = [cube, line, sphere, text, cylinder, arrow]
    if k == 3:
        markers[2] = marker_msg(2, ns="b", id=3, action=2)  # DELETE
    if k == 5:
        markers = [cube, sphere, marker_msg(0, ns="b", action=3)]  # drawn, then DELETEALL of namespace b: cleared
    return cdr(T("visualization_msgs/msg/MarkerArray")(markers))


def _path(k: int) -> bytes:
    stamped = [T("geometry_msgs/msg/PoseStamped")(header("odom"), pose(x, k, 0)) for x in range(3)]
    return cdr(T("nav_msgs/msg/Path")(header("odom"), stamped))


def _pose(k: int) -> bytes:
    return cdr(T("geometry_msgs/msg/PoseStamped")(header("odom"), pose(k, 0, 0, quat(0, 0, 0, 1))))


def _poses(k: int) -> bytes:
    return cdr(T("geometry_msgs/msg/PoseArray")(header("odom"), [pose(k, y, 0) for y in range(2)]))


def _fix(k: int) -> bytes:
    status = T("sensor_msgs/msg/NavSatStatus")(0, 1)
    return cdr(T("sensor_msgs/msg/NavSatFix")(header("gps"), status, 48.0 + k, 2.0, 30.0 + k, np.zeros(9), 0))


def _battery(k: int) -> bytes:
    cells = np.zeros(0, np.float32)
    values = (24.0 - k, 30.0, -3.0, 10.0, 20.0, 20.0, 0.8)
    return cdr(T("sensor_msgs/msg/BatteryState")(header(""), *values, 2, 1, 2, True, cells, cells, "base", "SN1"))


TOPICS = {  # topic → (type, message maker)
    "/imu": ("sensor_msgs/msg/Imu", _imu),
    "/rosout": ("rcl_interfaces/msg/Log", _log),
    "/diagnostics": ("diagnostic_msgs/msg/DiagnosticArray", _diagnostics),
    "/markers": ("visualization_msgs/msg/MarkerArray", _markers),
    "/path": ("nav_msgs/msg/Path", _path),
    "/pose": ("geometry_msgs/msg/PoseStamped", _pose),
    "/poses": ("geometry_msgs/msg/PoseArray", _poses),
    "/fix": ("sensor_msgs/msg/NavSatFix", _fix),
    "/battery": ("sensor_msgs/msg/BatteryState", _battery),
}
MESSAGES = sorted(
    (
        TopicMessage(T0 + k * S // 10 + i, topic, msgtype, make(k))
        for i, (topic, (msgtype, make)) in enumerate(TOPICS.items())
        for k in range(6)
    ),
    key=lambda m: m.time_ns,
)
"""Six messages a topic, 0.1 s apart (the topics 1 ns apart in each step), in receive order."""


class _PerMessage:
    """Logging as it was before issue 46: each row one ``rec.log`` at its time."""

    def __init__(self, rec: rr.RecordingStream) -> None:
        self.rec = rec

    def at(self, time_ns: int) -> None:
        set_time(self.rec, "time", time_ns, "timestamp")

    def log(self, entity: str, *archetypes: Any, static: bool = False) -> None:
        self.rec.log(entity, *archetypes, static=static)

    def take(self, entity: str, item: object, frame: str) -> bool:
        return False  # every item as its archetypes

    def send(self, *entities: str) -> None:
        pass

    def window_end(self, *, everything: bool = False) -> None:
        pass


def _record(path: Path, how: str) -> dict[str, Rows]:
    """The messages through a display feed into ``path``: ``before`` (per message), ``batch`` (pushed in two
    stretches, held runs) or ``live`` (logged as they come, in batches of 7)."""
    rec = rr.RecordingStream(f"test_row_columns_{how}")
    rec.save(path)
    feed = DisplayFeed(
        Notices(rec),
        clock="timestamp",
        fixed_frame="odom",
        topics={t: m for t, (m, _) in TOPICS.items()},
        hold=how == "batch",
    )
    if how == "before":
        feed.rows = _PerMessage(rec)  # type: ignore[assignment]
    if how == "live":
        feed.push(MESSAGES[:1])  # (anchors the entities, as a replay's first push does)
        feed._pending.clear()
        for i in range(0, len(MESSAGES), 7):
            feed.log(*MESSAGES[i : i + 7])
    else:
        middle = MESSAGES[len(MESSAGES) // 2].time_ns
        feed.push(MESSAGES)
        feed.until(middle)
        feed.until(None)
    feed.finish()
    rec.flush()
    rr.disconnect(recording=rec)
    return {**read_recording(path), "path": path}  # type: ignore[dict-item]


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, Rows]]:
    folder = tmp_path_factory.mktemp("row_columns")
    return {how: _record(folder / f"{how}.rrd", how) for how in ("before", "batch", "live")}


@pytest.mark.parametrize("how", ["batch", "live"])
def test_the_recording_is_the_one_per_message_logging_made(recordings: dict[str, dict[str, Rows]], how: str) -> None:
    before = rows_in_order(recordings["before"]["path"], tuple(TOPICS))
    after = rows_in_order(recordings[how]["path"], tuple(TOPICS))
    assert sorted(after) == sorted(before)
    for entity in before:
        assert after[entity] == before[entity], entity


def _deserialized(topic: str) -> list[tuple[int, Any]]:
    return [(m.time_ns, TS.deserialize_cdr(m.data, m.msgtype)) for m in MESSAGES if m.topic == topic]


def _drawn(rows: Rows, column: str) -> list[tuple[int, Any]]:
    return [(t, v) for t, v in zip(rows.times, rows.temporal.get(column, []), strict=False) if v is not None]


@pytest.mark.parametrize("how", ["batch", "live"])
def test_the_values_are_the_messages(recordings: dict[str, dict[str, Rows]], how: str) -> None:
    got = recordings[how]
    imu = _deserialized("/imu")
    rates = _drawn(got["/imu/angular_velocity"], "Scalars:scalars")
    assert [t for t, _ in rates] == [t for t, _ in imu]
    for (_, values), (_, msg) in zip(rates, imu, strict=True):
        v = msg.angular_velocity
        np.testing.assert_allclose(values, [v.x, v.y, v.z])
    axes = _drawn(got["/imu"], "Arrows3D:vectors")
    assert [t for t, _ in axes] == [t for t, _ in imu]
    for (_, vectors), (_, msg) in zip(axes, imu, strict=True):
        x, y, z, w = msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w
        rotation = np.array(  # the unit quaternion's rotation matrix, by hand; its columns are the rotated axes
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        np.testing.assert_allclose(vectors, rotation.T * 0.3, atol=1e-6)
    lines = _drawn(got["/rosout"], "TextLog:text")
    assert [(t, text) for t, text in lines] == [
        (t, [f"[node] {m.msg} (a.cpp:f:{m.line})"]) for t, m in _deserialized("/rosout")
    ]
    states = _drawn(got["/diagnostics/motor_0"], "StateChange:state")
    levels = {0: "OK", 1: "WARN", 2: "ERROR"}
    assert states == [
        (t, [f"{levels[m.status[0].level]}: {m.status[0].message}"]) for t, m in _deserialized("/diagnostics")
    ]
    cube = _drawn(got["/markers/a/1"], "InstancePoses3D:translations")
    assert cube == [(t, [[m.markers[0].pose.position.x, 0.0, 0.0]]) for t, m in _deserialized("/markers")]
    strip = _drawn(got["/markers/a/2"], "LineStrips3D:strips")
    assert [t for t, _ in strip] == [t for t, m in _deserialized("/markers") if any(mk.type == 4 for mk in m.markers)]
    fixes = _drawn(got["/fix"], "GeoPoints:positions")
    assert fixes == [(t, [[m.latitude, m.longitude]]) for t, m in _deserialized("/fix")]
    voltage = _drawn(got["/battery/voltage"], "Scalars:scalars")
    assert voltage == [(t, [m.voltage]) for t, m in _deserialized("/battery")]
    path = _drawn(got["/path"], "LineStrips3D:strips")
    assert path == [
        (t, [[[p.pose.position.x, p.pose.position.y, 0.0] for p in m.poses]]) for t, m in _deserialized("/path")
    ]


def test_a_delete_and_a_deleteall_clear_at_their_times(recordings: dict[str, dict[str, Rows]]) -> None:
    markers = [t for t, _ in _deserialized("/markers")]
    for how in ("batch", "live"):
        sphere = recordings[how]["/markers/b/3"]
        clears = [t for t, v in zip(sphere.times, sphere.temporal["Clear:is_recursive"], strict=False) if v == [True]]
        # drawn at 0, 1, 2 with a 0.25 s lifetime (each redraw before it ends); deleted at 3; drawn at 4; DELETEALL 5
        assert clears == [markers[3], markers[5]]


def test_runs_are_sent_as_columns_of_many_rows(tmp_path: Path) -> None:
    """A topic's rows go out in one ``send_columns`` per run, not one call per message."""
    rec = rr.RecordingStream("test_row_columns_calls")
    rows = RowColumns(rec, "time", "timestamp", hold=True)
    calls: list[tuple[str, int]] = []
    real = row_columns.send
    row_columns.send = lambda rec, entity, timeline, times, columns: calls.append((entity, len(times)))  # type: ignore[assignment]
    try:
        for k in range(100):
            rows.at(T0 + k)
            rows.log("/imu/rates", rr.Scalars([1.0, 2.0, 3.0]))
            rows.log("/log", rr.TextLog(f"line {k}"))
        rows.window_end()
        assert calls == []  # a batch run holds its runs across windows
        rows.window_end(everything=True)
    finally:
        row_columns.send = real  # type: ignore[assignment]
    assert calls == [("/imu/rates", 100), ("/log", 100)]
