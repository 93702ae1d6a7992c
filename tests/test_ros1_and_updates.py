"""Bags beyond ROS 2's own through the real CLI: a real ROS 1 bag (recorded by ROS 1's rosbag, see
tests/data/bags/ros1/README.md) replayed like a ROS 2 one, its /tf against rosbags' own ROS 1 reader; and nav2's map
updates (map_msgs/OccupancyGridUpdate) applied to their map as RViz's Map display does."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from conftest import REPO, cli
from rosbags.rosbag1 import Reader as Ros1Reader
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rrd import read_recording, tf_by_child

from r2d2_viz.msgs.typestore import typestore

ROS1_BAG = REPO / "tests" / "data" / "bags" / "ros1" / "example-lz4.bag"
T0 = 1_700_000_000_000_000_000


def _ros1_tf() -> list[tuple[int, str, str, tuple[float, float, float]]]:
    """(receive ns, parent, child, translation) of every /tf transform, by rosbags' ROS 1 reader and deserializer
    with the bag's own definitions."""
    store = get_typestore(Stores.EMPTY)
    out = []
    with Ros1Reader(ROS1_BAG) as reader:
        for c in reader.connections:
            store.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        for c, t, raw in reader.messages([c for c in reader.connections if c.topic in ("/tf", "tf")]):
            msg = store.deserialize_ros1(raw, c.msgtype)
            for tr in msg.transforms:
                v = tr.transform.translation
                out.append((t, tr.header.frame_id.lstrip("/"), tr.child_frame_id.lstrip("/"), (v.x, v.y, v.z)))
    return out


def test_a_real_ros1_bag_replays_its_tf_as_rosbags_reads_it(tmp_path: Path) -> None:
    out = tmp_path / "ros1.rrd"
    result = cli("--bag", str(ROS1_BAG), "--save", str(out))
    assert result.returncode == 0, result.stderr
    expected = _ros1_tf()
    assert expected  # the tf2 demo's turtles
    got = tf_by_child(read_recording(out))
    for child in {c for _, _, c, _ in expected}:
        mine = [(t, v) for t, _, c, v in expected if c == child]
        rows = got[child]
        assert sorted(rows.times) == [t for t, _ in mine]
        translations = [r for r in rows.temporal["Transform3D:translation"] if r is not None]
        np.testing.assert_allclose(np.vstack(translations), np.array([v for _, v in mine]), atol=1e-6)


def _grid(cells: list[int]) -> bytes:
    ts = typestore()
    T = ts.types
    info = T["nav_msgs/msg/MapMetaData"](
        T["builtin_interfaces/msg/Time"](0, 0),
        0.5,
        3,
        2,
        T["geometry_msgs/msg/Pose"](
            T["geometry_msgs/msg/Point"](0.0, 0.0, 0.0), T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0)
        ),
    )
    header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](1, 0), "map")
    msg = T["nav_msgs/msg/OccupancyGrid"](header, info, np.array(cells, dtype=np.int8))
    return bytes(ts.serialize_cdr(msg, "nav_msgs/msg/OccupancyGrid"))


def _bag(path: Path, messages: list[tuple[str, str, int, bytes]]) -> Path:
    ts = typestore()
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections: dict[str, object] = {}
        for topic, msgtype, t, data in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=ts)
            writer.write(connections[topic], t, data)  # type: ignore[arg-type]
    return path


def _textures(out: Path) -> list[bytes]:
    rows = read_recording(out)["/map"]
    return [
        bytes(np.asarray(v).tobytes()) for v in rows.temporal.get("Mesh3D:albedo_texture_buffer", []) if v is not None
    ]


def test_a_map_update_draws_what_the_updated_map_draws(tmp_path: Path) -> None:
    ts = typestore()
    T = ts.types
    before = [0, 0, 0, 0, 0, 0]  # 3 x 2 cells, all free
    after = [0, 0, 0, 0, 100, 100]  # the update: cells (1, 1) and (2, 1) occupied (a 2 x 1 patch at x=1, y=1)
    update = T["map_msgs/msg/OccupancyGridUpdate"](
        T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](2, 0), "map"),
        1,
        1,
        2,
        1,
        np.array([100, 100], np.int8),
    )
    updated = _bag(
        tmp_path / "updated",
        [
            ("/map", "nav_msgs/msg/OccupancyGrid", T0, _grid(before)),
            (
                "/map_updates",
                "map_msgs/msg/OccupancyGridUpdate",
                T0 + 10**9,
                bytes(ts.serialize_cdr(update, "map_msgs/msg/OccupancyGridUpdate")),
            ),
        ],
    )
    direct = _bag(tmp_path / "direct", [("/map", "nav_msgs/msg/OccupancyGrid", T0, _grid(after))])
    drawn = {}
    for name, bag in (("updated", updated), ("direct", direct)):
        out = tmp_path / f"{name}.rrd"
        result = cli("--bag", str(bag), "--save", str(out))
        assert result.returncode == 0, result.stderr
        assert "map_updates" not in result.stderr  # drawn, not "no display"
        drawn[name] = _textures(out)
    assert len(drawn["updated"]) == 2 and len(drawn["direct"]) == 1
    assert drawn["updated"][0] != drawn["updated"][1]  # the update changed the drawing…
    assert drawn["updated"][1] == drawn["direct"][0]  # …into what the updated map draws
