"""``r2d2-viz --save lap.mcap``: a rosbag2 read back with rosbags' own reader (independent of ours)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yourdfpy
from conftest import cli
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from ruamel.yaml import YAML

TS = get_typestore(Stores.ROS2_HUMBLE)


def test_a_run_saved_as_a_bag_has_what_robot_state_publisher_would_publish(tmp_path: Path, tutorial_urdf) -> None:
    bag = tmp_path / "lap.mcap"
    result = cli("--save", str(bag), "--duration", "1")
    assert result.returncode == 0, result.stderr
    assert (bag / "metadata.yaml").is_file() and not list(tmp_path.glob(".lap*"))
    with Reader(bag) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
        messages: dict[str, list] = {}
        for connection, stamp, data in reader.messages():
            messages.setdefault(connection.topic, []).append((stamp, TS.deserialize_cdr(data, connection.msgtype)))
    assert counts == {"/robot_description": 1, "/tf_static": 1, "/joint_states": 30, "/tf": 30}
    assert all(p.durability.name == "TRANSIENT_LOCAL" for t in ("/tf_static", "/robot_description") for p in qos[t])
    assert messages["/robot_description"][0][1].data == tutorial_urdf.read_text()
    # /tf_static: the R2D2's fixed joints, as yourdfpy reads their origins
    urdf = yourdfpy.URDF.load(str(tutorial_urdf), load_meshes=False, build_scene_graph=False)
    fixed = {j.child: (j.parent, j.origin) for j in urdf.robot.joints if j.type == "fixed"}
    static = {t.child_frame_id: t for t in messages["/tf_static"][0][1].transforms}
    assert set(static) == set(fixed)
    for child, (parent, origin) in fixed.items():
        t = static[child]
        assert t.header.frame_id == parent
        assert np.allclose(
            [t.transform.translation.x, t.transform.translation.y, t.transform.translation.z], origin[:3, 3], atol=1e-12
        )
    # /joint_states: the tutorial's joints, header stamps = the recording's times (1/30 s apart), /tf odom → axis
    stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in messages["/joint_states"]]
    assert np.allclose(np.diff(stamps), 1e9 / 30, atol=1)
    assert sorted(messages["/joint_states"][0][1].name) == ["periscope", "swivel", "tilt"]
    odom = [m.transforms[0] for _, m in messages["/tf"]]
    assert {(t.header.frame_id, t.child_frame_id) for t in odom} == {("odom", "axis")}
    assert np.isclose(odom[0].transform.translation.x, 2.0)  # state_publisher.py: cos(0) * 2
    info = YAML(typ="safe").load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["storage_identifier"] == "mcap" and info["message_count"] == 62


def test_a_bag_cannot_go_to_a_live_sink(tmp_path: Path) -> None:
    result = cli("--save", str(tmp_path / "x.mcap"), "--realtime")
    assert result.returncode == 2 and "live sink or --realtime" in result.stderr and not list(tmp_path.iterdir())
