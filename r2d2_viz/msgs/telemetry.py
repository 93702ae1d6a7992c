"""What no RViz display draws, in its natural Rerun form: the robot's log (``rcl_interfaces/msg/Log``, ROS 1's
``rosgraph_msgs/Log``, ``std_msgs/String``) as log lines; its diagnostics (``DiagnosticArray``) as per-status
states; ``Imu`` (its orientation as axes in its frame, rates and accelerations plotted), ``NavSatFix`` (a point on a
map), the scalar sensors, ``BatteryState`` and std_msgs' numbers as plots. Only the Imu's axes are drawn in 3D: the
rest is :data:`~r2d2_viz.msgs.shapes.Plain`, in a ``Decoded`` without a frame."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any

import numpy as np

from r2d2_viz.msgs.geometry import header_of, quat_matrix
from r2d2_viz.msgs.shapes import (
    Arrows,
    Decoded,
    DecodeOptions,
    GeoPoint,
    LogLine,
    Pose,
    Series,
    Shape,
    Status,
    Statuses,
)
from r2d2_viz.msgs.typestore import MsgError, deserialize

ROS2_LEVELS = ((50, "CRITICAL"), (40, "ERROR"), (30, "WARN"), (20, "INFO"))
"""rcl_interfaces/msg/Log's levels (10 DEBUG, 20 INFO, 30 WARN, 40 ERROR, 50 FATAL) to Rerun's ``TextLogLevel``
names, whose FATAL is called CRITICAL; a value between two levels reads as the lower one, below 20 as DEBUG."""
ROS1_LEVELS = ((16, "CRITICAL"), (8, "ERROR"), (4, "WARN"), (2, "INFO"))
"""rosgraph_msgs/Log's levels (1 DEBUG, 2 INFO, 4 WARN, 8 ERROR, 16 FATAL), likewise."""
DIAGNOSTIC_LEVELS = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}
"""diagnostic_msgs/DiagnosticStatus levels (ROS 1 and ROS 2 alike)."""


def log_level(level: int, levels: tuple[tuple[int, str], ...] = ROS2_LEVELS) -> str:
    """A ROS log level as Rerun names it."""
    return next((name for threshold, name in levels if level >= threshold), "DEBUG")


def shown(text: str) -> str:
    """Text from a bag as a log view should show it: a terminal's colour codes (``ESC[94m…ESC[0m``, which
    ros2_control's spawner writes into ``/rosout``, as the Webots e-puck bag holds them) dropped — the viewer
    printed them as they are —, and every other control character shown as an escape (``\\x1b``), never passed
    on; line breaks and tabs kept."""
    return _CONTROL.sub(lambda m: f"\\x{ord(m.group()):02x}", _COLOURS.sub("", text))


_COLOURS = re.compile(r"\x1b\[[0-9;:]*m")
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def _log_text(msg: object) -> str:
    """``[node] message (file:function:line)``, as rqt_console shows a line."""
    name, text = getattr(msg, "name", ""), getattr(msg, "msg", "")
    where = f"{msg.file}:{msg.function}:{msg.line}" if getattr(msg, "file", "") else ""  # type: ignore[attr-defined]
    return shown(f"[{name}] {text}" + (f" ({where})" if where else ""))


def decode_log(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A ROS 2 ``/rosout`` line."""
    msg = deserialize(data, "rcl_interfaces/msg/Log")
    stamp = int(msg.stamp.sec) * 1_000_000_000 + int(msg.stamp.nanosec)
    return Decoded("", stamp, (LogLine(log_level(int(msg.level)), _log_text(msg)),))


def decode_ros1_log(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A ROS 1 ``/rosout`` line (rosgraph_msgs/Log: its own levels)."""
    msg = deserialize(data, "rosgraph_msgs/msg/Log")
    _, stamp = header_of(msg)
    return Decoded("", stamp, (LogLine(log_level(int(msg.level), ROS1_LEVELS), _log_text(msg)),))


def decode_string(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A std_msgs/String as a log line without a level."""
    return Decoded("", 0, (LogLine("", shown(str(deserialize(data, "std_msgs/msg/String").data))),))


def status_parts(name: str) -> tuple[str, ...]:
    """A status name as entity path parts: split at '/' (``/diagnostics_agg``'s ``/Robot/Motors`` nests), each
    part's runs of other characters than letters, digits (of any script), ``_``, ``-`` and ``.`` as one ``_``
    (``motor: left`` → ``motor_left``: no escapes in the viewer's lane names), empty parts dropped; a name with none
    is itself (escaped where logged)."""
    parts = (_UNSAFE.sub("_", p).strip("_") for p in name.split("/"))
    return tuple(p for p in parts if p) or (name.strip() or "_",)


_UNSAFE = re.compile(r"[^\w.-]+")  # letters and digits of any script (電池) kept


MAX_STATUSES = 1000
"""More statuses in one DiagnosticArray (an entity each) and the message is refused (said once per topic, counted):
a robot has tens."""
MAX_VALUES = 4096
"""A status's key/values beyond these are one more key saying how many are not shown (the status is)."""


def decode_diagnostics(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A DiagnosticArray: each status's level, message and key/values."""
    msg = deserialize(data, "diagnostic_msgs/msg/DiagnosticArray")
    _, stamp = header_of(msg)
    if len(msg.status) > MAX_STATUSES:
        raise MsgError(f"{len(msg.status)} statuses: more than {MAX_STATUSES}")
    statuses = tuple(
        Status(
            status_parts(str(s.name)),
            DIAGNOSTIC_LEVELS.get(int(s.level), f"LEVEL {int(s.level)}"),
            shown(str(s.message)),
            shown(str(s.hardware_id)),
            tuple((shown(str(kv.key)), shown(str(kv.value))) for kv in s.values[:MAX_VALUES])
            + ((("key/values not shown", str(len(s.values) - MAX_VALUES)),) if len(s.values) > MAX_VALUES else ()),
            shown(str(s.name)),
        )
        for s in msg.status
    )
    return Decoded("", stamp, (Statuses(statuses),))


IMU_AXIS = 0.3
"""The Imu's orientation as x, y, z axes this long (m), red, green, blue."""
AXIS_COLORS = np.array([[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]], dtype=np.uint8)
NO_FIX = -1
"""NavSatStatus.STATUS_NO_FIX: the position means nothing."""
SCALAR_SENSORS = {
    "sensor_msgs/msg/Temperature": "temperature",
    "sensor_msgs/msg/FluidPressure": "fluid_pressure",
    "sensor_msgs/msg/RelativeHumidity": "relative_humidity",
    "sensor_msgs/msg/Illuminance": "illuminance",
}
"""Each scalar sensor's field (its ``variance`` is left out)."""
BATTERY = ("voltage", "current", "charge", "percentage", "temperature")
"""BatteryState's fields plotted, each its own plot entity (their units differ)."""
NUMBERS = tuple(
    f"std_msgs/msg/{t}"
    for t in ("Float32", "Float64", "Int8", "Int16", "Int32", "Int64", "UInt8", "UInt16", "UInt32", "UInt64", "Bool")
)


def _vector(v: Any) -> np.ndarray:
    return np.array([v.x, v.y, v.z], dtype=np.float64)


def quat_norm(q: np.ndarray) -> np.ndarray:
    """The norm of quaternions ``(..., 4)``, summed in one order (``np.linalg.norm`` 's BLAS sum may differ by an ulp
    from a vectorised one: a block of messages gets the very values one message gets)."""
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.asarray(np.sqrt(((x * x + y * y) + z * z) + w * w))


def decode_imu(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """An Imu: its orientation as axes (none when it is unknown: covariance[0] = -1, or not finite or zero) and
    its angular velocity and linear acceleration as plots."""
    msg = deserialize(data, "sensor_msgs/msg/Imu")
    frame, stamp = header_of(msg)
    items: list[Shape] = []
    o = msg.orientation
    q = np.array([o.x, o.y, o.z, o.w], dtype=np.float64)
    norm = float(quat_norm(q))
    if np.isfinite(norm) and norm > 1e-9 and float(msg.orientation_covariance[0]) != -1.0:
        x, y, z, w = (q / norm).tolist()
        axes = (quat_matrix((x, y, z, w)).T * IMU_AXIS).astype(np.float32)  # rows: the rotated x, y, z axes
        items.append(Arrows(np.zeros((3, 3), np.float32), axes, AXIS_COLORS, 0.01, Pose()))
    xyz = ("x", "y", "z")
    items.append(Series("angular_velocity", xyz, _vector(msg.angular_velocity)))
    items.append(Series("linear_acceleration", xyz, _vector(msg.linear_acceleration)))
    return Decoded(frame, stamp, tuple(items))


def decode_navsatfix(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A NavSatFix as a point on a map (nothing without a fix or with a position that is not finite) and its
    altitude plotted."""
    msg = deserialize(data, "sensor_msgs/msg/NavSatFix")
    _, stamp = header_of(msg)
    lat, lon, alt = float(msg.latitude), float(msg.longitude), float(msg.altitude)
    items: list[Shape] = [Series("altitude", ("altitude",), np.array([alt]))]
    if int(msg.status.status) != NO_FIX and np.isfinite([lat, lon]).all() and abs(lat) <= 90 and abs(lon) <= 180:
        items.insert(0, GeoPoint(lat, lon))
    return Decoded("", stamp, tuple(items))


def _scalar_sensor(msgtype: str) -> Callable[[bytes | memoryview, DecodeOptions], Decoded]:
    field = SCALAR_SENSORS[msgtype]

    def decode(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
        msg = deserialize(data, msgtype)
        _, stamp = header_of(msg)
        return Decoded("", stamp, (Series("", (field,), np.array([float(getattr(msg, field))])),))

    decode.__doc__ = f"A {msgtype.rsplit('/', 1)[-1]}'s {field}, plotted."
    return decode


SCALAR_DECODERS = {msgtype: _scalar_sensor(msgtype) for msgtype in SCALAR_SENSORS}


def decode_battery(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A BatteryState's voltage, current, charge, percentage and temperature, each plotted (NaN: not measured)."""
    msg = deserialize(data, "sensor_msgs/msg/BatteryState")
    _, stamp = header_of(msg)
    items = tuple(Series(f, (f,), np.array([float(getattr(msg, f))])) for f in BATTERY)
    return Decoded("", stamp, items)


def _number(msgtype: str) -> Callable[[bytes | memoryview, DecodeOptions], Decoded]:
    def decode(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
        value = deserialize(data, msgtype).data
        return Decoded("", 0, (Series("", ("data",), np.array([float(value)])),))

    decode.__doc__ = f"A {msgtype}, plotted."
    return decode


NUMBER_DECODERS = {msgtype: _number(msgtype) for msgtype in NUMBERS}


KINDS: dict[str, bool] = {}
"""Status key → whether it is a number: its first value, in any status of any topic (Rerun fixes a component's type
at its first log, process-wide); a later value of the other kind goes beside it (``KEY (text)``, the number NaN)."""


_EMPTY = {True: np.zeros(0, dtype=np.float64), False: np.zeros(0, dtype=np.str_)}
"""No value, typed (an untyped empty list is dropped, not logged)."""


def _parsed(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def status_fields(status: Status, known: set[str]) -> dict[str, object]:
    """A status's fields as logged: its level, message, hardware id and key/values (see :data:`KINDS`); ``known``:
    the fields earlier statuses on its entity had (updated) — those this one lacks are empty (cleared, not
    inherited)."""
    out: dict[str, object] = {"name": status.name, "level": status.level, "message": status.message}
    out["hardware_id"] = status.hardware_id
    for key, text in status.values:
        if key in out:
            key = f"{key} (value)"
        value = _parsed(text)
        numeric = KINDS.setdefault(key, value is not None)
        out[key] = [(math.nan if value is None else value)] if numeric else [text]
        if numeric and value is None:
            out[f"{key} (text)"] = [text]
    out |= {key: _EMPTY[KINDS.get(key, False) and not key.endswith(" (text)")] for key in known - out.keys()}
    known.update(out)
    return out
