"""``--bag run.bag --save out.mcap``: a ROS 1 bag (written by rosbags' ROS 1 writer with Noetic's types) becomes a
ROS 2 bag that rosbags' ROS 2 reader reads back with Humble's types: every topic, the same values, ROS 2 names."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from conftest import cli
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

NOETIC = get_typestore(Stores.ROS1_NOETIC)
NOETIC.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
HUMBLE = get_typestore(Stores.ROS2_HUMBLE)
T0 = 1_700_000_000_000_000_000


def _ros1_bag(path: Path) -> Path:
    T = NOETIC.types
    with Ros1Writer(path) as writer:
        joints = writer.add_connection("joint_states", "sensor_msgs/msg/JointState", typestore=NOETIC)  # no slash
        tf = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=NOETIC)
        for k in range(20):
            t = T0 + k * 10_000_000
            stamp = T["builtin_interfaces/msg/Time"](*divmod(t, 10**9))
            header = T["std_msgs/msg/Header"](k, stamp, "base")
            msg = T["sensor_msgs/msg/JointState"](
                header, ["a", "b"], np.array([k, -k], float), np.zeros(0), np.zeros(0)
            )
            writer.write(joints, t, NOETIC.serialize_ros1(msg, "sensor_msgs/msg/JointState"))
            transform = T["geometry_msgs/msg/Transform"](
                T["geometry_msgs/msg/Vector3"](0.1 * k, 0.0, 0.0), T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0)
            )
            edge = T["geometry_msgs/msg/TransformStamped"](header, "odom", transform)
            writer.write(tf, t, NOETIC.serialize_ros1(T["tf2_msgs/msg/TFMessage"]([edge]), "tf2_msgs/msg/TFMessage"))
    return path


def test_a_ros1_bag_saved_as_mcap_reads_back_in_ros2(tmp_path: Path) -> None:
    bag = _ros1_bag(tmp_path / "run.bag")
    out = tmp_path / "run_ros2"
    result = cli("--bag", str(bag), "--save", str(out.with_suffix(".mcap")))
    assert result.returncode == 0, result.stderr
    assert "r2d2-viz: 40 messages converted" in result.stderr
    got: dict[str, list] = {}
    with Reader(out.with_suffix(".mcap")) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types == {"/joint_states": "sensor_msgs/msg/JointState", "/tf": "tf2_msgs/msg/TFMessage"}
        for c, t, data in reader.messages():
            got.setdefault(c.topic, []).append((t, HUMBLE.deserialize_cdr(data, c.msgtype)))
    assert [t for t, _ in got["/joint_states"]] == [T0 + k * 10_000_000 for k in range(20)]
    assert [list(m.position) for _, m in got["/joint_states"]] == [[k, -k] for k in range(20)]
    assert [list(m.name) for _, m in got["/joint_states"]] == [["a", "b"]] * 20
    assert [m.transforms[0].transform.translation.x for _, m in got["/tf"]] == [0.1 * k for k in range(20)]
    assert {m.transforms[0].child_frame_id for _, m in got["/tf"]} == {"odom"}
