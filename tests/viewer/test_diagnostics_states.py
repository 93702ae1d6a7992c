"""Issue 37's finding 5 (and 2 for diagnostics), as found: two statuses sharing a key, one numeric one text
(``Temperature: 45.2`` / ``N/A``); a status with 1,200 key/values beside an e-stop ERROR; status names without
ASCII letters or digits (Japanese); a status OK again still showing the older error's key/values. A bag rosbags
wrote, the CLI in a subprocess, the recording read back; what each message holds comes from rosbags' deserializer."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from conftest import cli
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from rrd import Rows, read_recording

TS = get_typestore(Stores.ROS2_HUMBLE)
T = TS.types
T0 = 1_700_000_000_000_000_000
ARRAY = "diagnostic_msgs/msg/DiagnosticArray"


def _status(name: str, level: int, message: str, values: list[tuple[str, str]]) -> Any:
    kvs = [T["diagnostic_msgs/msg/KeyValue"](k, v) for k, v in values]
    return T["diagnostic_msgs/msg/DiagnosticStatus"](level, name, message, "hw", kvs)


def _bag(path: Path, arrays: list[list[Any]]) -> list[tuple[int, Any]]:
    out = []
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/diagnostics", ARRAY, typestore=TS)
        for k, statuses in enumerate(arrays):
            t = T0 + k * 10**9
            header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](*divmod(t, 10**9)), "")
            data = bytes(TS.serialize_cdr(T[ARRAY](header, statuses), ARRAY))
            writer.write(conn, t, data)
            out.append((t, TS.deserialize_cdr(data, ARRAY)))
    return out


def _latest(rows: Rows, column: str, time_ns: int) -> Any:
    found = None
    for t, value in zip(rows.times, rows.temporal.get(column, []), strict=False):
        if t <= time_ns and value is not None:
            found = value
    return found


def _lane(recording: dict[str, Rows], name: str) -> Rows:
    [rows] = [
        r
        for e, r in recording.items()
        if r.temporal.get("DiagnosticStatus:name") and any(v == [name] for v in r.temporal["DiagnosticStatus:name"])
    ]
    return rows


def test_every_status_and_key_of_each_message_is_shown_and_nothing_older(tmp_path: Path) -> None:
    many = [(f"cell {i}", str(3.5 + i / 1000)) for i in range(1200)]
    arrays = [
        [
            _status("left motor", 0, "ok", [("Temperature", "45.2")]),
            _status("right motor", 1, "no sensor", [("Temperature", "N/A")]),
            _status("電池", 0, "ok", [("残量", "80")]),
            _status("モーター", 2, "overcurrent", [("Error code", "17"), ("Last error", "overcurrent")]),
            _status("battery cells", 0, "ok", many),
            _status("e-stop", 2, "pressed", []),
        ],
        [
            _status("left motor", 0, "ok", [("Temperature", "N/A")]),
            _status("right motor", 0, "ok", [("Temperature", "40.5")]),
            _status("電池", 0, "ok", [("残量", "79")]),
            _status("モーター", 0, "ok", []),  # OK again: its error's key/values are gone
        ],
    ]
    written = _bag(tmp_path / "bag", arrays)
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(tmp_path / "bag"), "--save", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "RerunWarning" not in result.stderr, result.stderr
    recording = read_recording(out)
    names = {s.name for _, msg in written for s in msg.status}
    lanes = {e for e, r in recording.items() if r.temporal.get("DiagnosticStatus:name")}
    assert len(lanes) == len(names), sorted(lanes)  # one lane per distinct name
    for t, msg in written:
        for status in msg.status:
            rows = _lane(recording, status.name)
            assert _latest(rows, "DiagnosticStatus:message", t) == [status.message], (status.name, t)
            want = {kv.key: kv.value for kv in status.values}
            shown = {}
            for column in [c for c in rows.temporal if c.startswith("DiagnosticStatus:")]:
                key = column.split(":", 1)[1]
                if key in ("name", "level", "message", "hardware_id") or key.endswith(" (text)"):
                    continue
                value = _latest(rows, column, t)
                if value:
                    text = _latest(rows, f"DiagnosticStatus:{key} (text)", t)
                    shown[key] = text[0] if text else value[0]
            assert set(shown) == set(want), (status.name, t, set(shown) ^ set(want))
            for key, text in want.items():
                got = shown[key]
                assert got == text if isinstance(got, str) else abs(got - float(text)) < 1e-9, (status.name, key)
