"""Write a demo bag for docs/log-and-diagnostics.png: the tutorial's R2D2 walking its circle for 20 s (/tf,
/joint_states, /robot_description) with a robot's log on /rosout, /diagnostics whose statuses change, an Imu and a
battery; written by rosbags (ROS 2 MCAP). Then: ``r2d2-viz --bag OUT --save demo.rrd`` and
``rerun demo.rrd --screenshot-to docs/log-and-diagnostics.png --window-size 1600x1000``."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

S = 1_000_000_000
T0 = 1_700_000_000 * S
STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types
LOG = [  # (second, level, node, text)
    (0.5, 20, "robot_state_publisher", "got segment axis"),
    (1.0, 20, "walker", "starting the lap"),
    (4.0, 10, "walker", "heading 0.62 rad"),
    (6.2, 30, "motor_driver", "left leg current 4.1 A above 4.0 A"),
    (8.0, 20, "walker", "periscope up"),
    (9.5, 40, "motor_driver", "left leg overcurrent: limiting torque"),
    (12.0, 30, "battery_monitor", "battery at 30 %"),
    (14.5, 20, "motor_driver", "left leg current back to 2.2 A"),
    (17.0, 50, "safety", "bumper pressed: e-stop"),
    (18.0, 20, "walker", "lap done"),
]


def _time(t_ns: int) -> Any:
    return T["builtin_interfaces/msg/Time"](*divmod(t_ns, S))


def _header(t_ns: int, frame: str = "") -> Any:
    return T["std_msgs/msg/Header"](_time(t_ns), frame)


def _status(name: str, level: int, message: str, values: dict[str, str]) -> Any:
    kv = [T["diagnostic_msgs/msg/KeyValue"](k, v) for k, v in values.items()]
    return T["diagnostic_msgs/msg/DiagnosticStatus"](level, name, message, "r2d2", kv)


def _diagnostics(t: float) -> list[Any]:
    current = 2.0 + (2.3 if 6 <= t < 14.5 else 0.0)
    motor = (0, "ok") if current < 4.0 else ((1, "current high") if t < 9.5 else (2, "overcurrent"))
    battery = 100 - 3.5 * t
    power = (0, "ok") if battery > 40 else (1, "low")
    bumper = (0, "clear") if t < 17 else (2, "pressed")
    camera = (0, "30 Hz") if not 11 <= t < 13 else (3, "no images")
    return [
        _status("motor_driver: left leg", *motor, {"current": f"{current:.2f}", "temperature": f"{40 + t:.1f}"}),
        _status("battery_monitor: main", *power, {"percentage": f"{battery:.0f}", "voltage": f"{24 - 0.1 * t:.2f}"}),
        _status("safety: bumper", *bumper, {}),
        _status("camera: head", *camera, {"rate": "30" if camera[0] == 0 else "0"}),
    ]


def _tf(t: float) -> Any:
    a = 2 * math.pi * t / 20
    v = T["geometry_msgs/msg/Vector3"](math.cos(a), math.sin(a), 0.8)
    q = T["geometry_msgs/msg/Quaternion"](0.0, 0.0, math.sin((a + math.pi / 2) / 2), math.cos((a + math.pi / 2) / 2))
    tr = T["geometry_msgs/msg/TransformStamped"](
        _header(T0 + int(t * S), "odom"), "axis", T["geometry_msgs/msg/Transform"](v, q)
    )
    return T["tf2_msgs/msg/TFMessage"]([tr])


def _imu(t: float, t_ns: int) -> Any:
    a = 2 * math.pi * t / 20
    q = T["geometry_msgs/msg/Quaternion"](0.0, 0.0, math.sin(a / 2), math.cos(a / 2))
    v3, cov = T["geometry_msgs/msg/Vector3"], np.zeros(9)
    rates, accel = v3(0.0, 0.05 * math.sin(3 * t), 2 * math.pi / 20), v3(0.3 * math.sin(2 * t), 0.3, 9.81)
    return T["sensor_msgs/msg/Imu"](_header(t_ns, "body"), q, cov, rates, cov, accel, cov)


def _battery(t: float, t_ns: int) -> Any:
    cells, current = np.zeros(0, np.float32), -2.0 - (2.3 if 6 <= t < 14.5 else 0.0)
    values = (24 - 0.1 * t, 30.0, current, 5.0, 10.0, 10.0, 1 - 0.035 * t, 2, 1, 2, True, cells, cells, "base", "r2")
    return T["sensor_msgs/msg/BatteryState"](_header(t_ns), *values)


def write(out: Path, urdf: str) -> Path:
    rows: list[tuple[str, str, int, Any]] = [
        ("/robot_description", "std_msgs/msg/String", T0, T["std_msgs/msg/String"](urdf))
    ]
    for k in range(20 * 30):  # 30 Hz
        t = k / 30
        t_ns = T0 + int(t * S)
        rows.append(("/tf", "tf2_msgs/msg/TFMessage", t_ns, _tf(t)))
        positions = np.array([-0.25 + 0.25 * math.sin(t), 2 * t, -0.25 + 0.25 * math.sin(t / 2)])
        js = T["sensor_msgs/msg/JointState"](
            _header(t_ns), ["tilt", "swivel", "periscope"], positions, np.zeros(0), np.zeros(0)
        )
        rows.append(("/joint_states", "sensor_msgs/msg/JointState", t_ns, js))
        if k % 3 == 0:  # 10 Hz
            rows.append(("/imu", "sensor_msgs/msg/Imu", t_ns, _imu(t, t_ns)))
        if k % 30 == 0:  # 1 Hz
            diagnostics = T["diagnostic_msgs/msg/DiagnosticArray"](_header(t_ns), _diagnostics(t))
            rows.append(("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", t_ns, diagnostics))
            rows.append(("/battery", "sensor_msgs/msg/BatteryState", t_ns, _battery(t, t_ns)))
    for t, level, node, text in LOG:
        t_ns = T0 + int(t * S)
        line = T["rcl_interfaces/msg/Log"](_time(t_ns), level, node, text, f"{node}.cpp", "update", 42)
        rows.append(("/rosout", "rcl_interfaces/msg/Log", t_ns, line))
    rows.sort(key=lambda r: r[2])
    with Writer(out, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections: dict[str, Any] = {}
        for topic, msgtype, t_ns, msg in rows:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=STORE)
            writer.write(connections[topic], t_ns, bytes(STORE.serialize_cdr(msg, msgtype)))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", type=Path, help="the bag folder to write")
    args = parser.parse_args()
    from r2d2_viz.robot.model import default_urdf_path

    print(write(args.out, default_urdf_path().read_text()))


if __name__ == "__main__":
    main()
