"""The log, diagnostics, sensors and numbers no display draws: levels as rqt_console names them (ROS 1's and
ROS 2's numbers, by hand from rcl_interfaces/msg/Log and rosgraph_msgs/Log), status names as entity parts, what an
Imu or a fix without data gives. Messages built and serialised by rosbags."""

from __future__ import annotations

import math

import numpy as np
import pytest
from msgs_build import T, cdr, header, quat, vec

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.registry import decode
from r2d2_viz.msgs.telemetry import ROS1_LEVELS, log_level, status_parts
from r2d2_viz.msgs.typestore import MsgError


@pytest.mark.parametrize(
    ("ros2", "ros1", "name"),
    [(10, 1, "DEBUG"), (20, 2, "INFO"), (30, 4, "WARN"), (40, 8, "ERROR"), (50, 16, "CRITICAL")],
)
def test_levels_as_rerun_names_them(ros2: int, ros1: int, name: str) -> None:
    assert log_level(ros2) == name and log_level(ros1, ROS1_LEVELS) == name


def test_levels_between_and_outside_read_as_the_one_below() -> None:
    assert [log_level(v) for v in (0, 25, 45, 255)] == ["DEBUG", "INFO", "ERROR", "CRITICAL"]
    assert [log_level(v, ROS1_LEVELS) for v in (0, 3, 127)] == ["DEBUG", "INFO", "CRITICAL"]


def test_status_names_as_entity_parts() -> None:
    assert status_parts("/Robot/Motors/Left") == ("Robot", "Motors", "Left")
    assert status_parts("motor: left") == ("motor_left",)
    assert status_parts("gps (rtk)/fix #2") == ("gps_rtk", "fix_2")
    assert status_parts("") == ("_",) and status_parts("//") == ("//",)  # no safe character: the name itself
    assert status_parts("電池/モーター 1") == ("電池", "モーター_1")  # letters and digits of any script are kept


def _imu(q, covariance0: float = 0.0) -> bytes:
    cov = np.zeros(9)
    first = cov.copy()
    first[0] = covariance0
    return cdr(T("sensor_msgs/msg/Imu")(header("imu"), q, first, vec(1, 2, 3), cov, vec(4, 5, 6), cov))


def test_an_imu_without_an_orientation_is_only_plotted() -> None:
    for data in (_imu(quat(0, 0, 0, 1), -1.0), _imu(quat(0, 0, 0, 0)), _imu(quat(math.inf, 0, 0, 1))):
        out = decode("sensor_msgs/msg/Imu", data)
        assert isinstance(out, shapes.Decoded)
        assert [type(i) for i in out.items] == [shapes.Series, shapes.Series]
        np.testing.assert_array_equal(out.items[1].values, [4, 5, 6])  # type: ignore[union-attr]


def test_a_fix_without_a_fix_is_no_point() -> None:
    def fix(status: int, lat: float) -> shapes.Decoded:
        status_msg = T("sensor_msgs/msg/NavSatStatus")(status=status, service=1)
        data = cdr(T("sensor_msgs/msg/NavSatFix")(header("gps"), status_msg, lat, 2.0, 3.0, np.zeros(9), 0))
        out = decode("sensor_msgs/msg/NavSatFix", data)
        assert isinstance(out, shapes.Decoded) and out.frame_id == ""  # on a map, in no TF frame
        return out

    assert fix(0, 48.5).items[0] == shapes.GeoPoint(48.5, 2.0)
    assert not any(isinstance(i, shapes.GeoPoint) for i in fix(-1, 48.5).items)  # STATUS_NO_FIX
    assert not any(isinstance(i, shapes.GeoPoint) for i in fix(0, math.nan).items)


def test_numbers_and_strings() -> None:
    out = decode("std_msgs/msg/UInt64", cdr(T("std_msgs/msg/UInt64")(data=2**63)))
    assert isinstance(out, shapes.Decoded) and out.items[0].values.tolist() == [2.0**63]  # type: ignore[union-attr]
    text = decode("std_msgs/msg/String", cdr(T("std_msgs/msg/String")(data="héllo")))
    assert isinstance(text, shapes.Decoded) and text.items == (shapes.LogLine("", "héllo"),)


def test_a_string_that_is_not_utf8_is_a_msg_error() -> None:
    data = bytearray(cdr(T("std_msgs/msg/String")(data="abcd")))
    data[8:12] = b"\xff\xfe\xfd\xfc"
    with pytest.raises(MsgError, match="utf-8"):
        decode("std_msgs/msg/String", bytes(data))


def test_a_diagnostic_array_of_thousands_of_statuses_is_refused() -> None:
    status = T("diagnostic_msgs/msg/DiagnosticStatus")
    many = [status(level=0, name=f"s{k}", message="", hardware_id="", values=[]) for k in range(1001)]
    data = cdr(T("diagnostic_msgs/msg/DiagnosticArray")(header=header(), status=many))
    with pytest.raises(MsgError, match="1001 statuses"):
        decode("diagnostic_msgs/msg/DiagnosticArray", data)
    out = decode(
        "diagnostic_msgs/msg/DiagnosticArray", cdr(T("diagnostic_msgs/msg/DiagnosticArray")(header(), many[:3]))
    )
    assert isinstance(out, shapes.Decoded) and len(out.items[0].items) == 3  # type: ignore[union-attr]
