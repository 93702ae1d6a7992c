"""Small R2D2 bags for the fleet tests, written by rosbags (tests/bagmaker.py), whose summary values are worked
out by hand here — each beside the motion it comes from.

``walk``: 9 samples 0.1 s apart. The base ``axis`` moves in ``odom`` through (0,0,0), (1,0,0), (2,0,0), (3,0,0),
(3,1,0), (3,2,0), (3,3,0), (3,4,0), (3,4,0): 3 m along x then 4 m along y = **7 m**; ``map → odom`` is static
(/tf_static, yawed 90° and shifted: a rigid motion, the length stays 7). Joints: swivel 0.3·k rad (0.3 rad per
0.1 s = **3 rad/s**, the fastest), tilt −0.02·k (0.2 rad/s), periscope 0. Duration 0.8 s. Topics: /robot_description,
/joint_states (9), /tf (9), /tf_static (1), /scan (3 LaserScans) → 5 topics; JointState 9, TFMessage 10,
LaserScan 3.

``turn``: 9 samples 0.1 s apart. ``odom → axis`` stays (1,0,0); ``map → odom`` (on /tf) is the identity for
k < 4, then yawed +90°: the base jumps from (1,0,0) to (0,1,0) in ``map`` once = **√2 m**. Joints: swivel 0,
tilt −0.02·k (0.2 rad/s), periscope 0 until k = 4, −0.1 m from k = 5 (0.1 m in 0.1 s = **1 m/s**, the fastest).
Duration 0.8 s. Topics: /robot_description, /joint_states (9), /tf (9) → 3; JointState 9, TFMessage 9.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from bagmaker import T0, TS, BagSpec, Header, joint_state, stamp, string, tf_message, write_bag

from r2d2_viz.robot.model import default_urdf_path

STEP_NS = 100_000_000
JOINTS = ["swivel", "tilt", "periscope"]
YAW90 = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))
IDENTITY = (0.0, 0.0, 0.0, 1.0)

WALK = {"distance_m": 7.0, "max_joint_speed": 3.0, "fastest_joint": "swivel", "duration_s": 0.8, "topics": 5}
WALK_MESSAGES = {"messages_JointState": 9, "messages_TFMessage": 10, "messages_LaserScan": 3}
TURN = {"distance_m": math.sqrt(2), "max_joint_speed": 1.0, "fastest_joint": "periscope", "duration_s": 0.8}
TURN_MESSAGES = {"messages_JointState": 9, "messages_TFMessage": 9, "messages_LaserScan": 0}


def laser_scan(t_ns: int) -> bytes:
    msg = TS.types["sensor_msgs/msg/LaserScan"](
        Header(stamp(t_ns), "axis"),
        -0.5,
        0.5,
        0.5,
        0.0,
        0.1,
        0.1,
        10.0,
        np.array([1.0, 2.0, 3.0], np.float32),
        np.zeros(0, np.float32),
    )
    return bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/LaserScan"))


def walk_bag(path: Path, *, storage: str = "mcap") -> Path:
    spec = BagSpec()
    spec.types["/scan"] = "sensor_msgs/msg/LaserScan"
    spec.add("/robot_description", T0, string(default_urdf_path().read_text()))
    spec.add("/tf_static", T0, tf_message([(T0, "map", "odom", (1.0, 2.0, 0.0), YAW90)]))
    path_xy = [(0, 0), (1, 0), (2, 0), (3, 0), (3, 1), (3, 2), (3, 3), (3, 4), (3, 4)]
    for k, (x, y) in enumerate(path_xy):
        t = T0 + k * STEP_NS
        spec.add("/joint_states", t, joint_state(t, JOINTS, [0.3 * k, -0.02 * k, 0.0]))
        spec.add("/tf", t, tf_message([(t, "odom", "axis", (float(x), float(y), 0.0), IDENTITY)]))
        if k in (1, 3, 5):
            spec.add("/scan", t, laser_scan(t))
    return write_bag(path, spec, storage=storage)


def turn_bag(path: Path, *, storage: str = "mcap") -> Path:
    spec = BagSpec()
    spec.add("/robot_description", T0, string(default_urdf_path().read_text()))
    for k in range(9):
        t = T0 + k * STEP_NS
        periscope = 0.0 if k <= 4 else -0.1
        spec.add("/joint_states", t, joint_state(t, JOINTS, [0.0, -0.02 * k, periscope]))
        yaw = IDENTITY if k < 4 else YAW90
        spec.add(
            "/tf", t, tf_message([(t, "map", "odom", (0.0, 0.0, 0.0), yaw), (t, "odom", "axis", (1, 0, 0), IDENTITY)])
        )
    return write_bag(path, spec, storage=storage)


def still_bag(path: Path, *, samples: int = 5, storage: str = "mcap") -> Path:
    """A plain bag of ``samples`` joint states (no transforms): for the conversion tests."""
    spec = BagSpec()
    spec.add("/robot_description", T0, string(default_urdf_path().read_text()))
    for k in range(samples):
        t = T0 + k * STEP_NS
        spec.add("/joint_states", t, joint_state(t, JOINTS, [0.01 * k, 0.0, 0.0]))
    return write_bag(path, spec, storage=storage)
