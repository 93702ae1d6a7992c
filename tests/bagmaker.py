"""Bags for the tests, written by ``rosbags`` itself (its own serializer and writer: independent of
:mod:`r2d2_viz.ros_out.bag_write`), in either storage and in metadata versions 1 to 9."""

from __future__ import annotations

import sqlite3
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from ruamel.yaml import YAML

TS = get_typestore(Stores.ROS2_HUMBLE)
JointState = TS.types["sensor_msgs/msg/JointState"]
Header = TS.types["std_msgs/msg/Header"]
Time = TS.types["builtin_interfaces/msg/Time"]
String = TS.types["std_msgs/msg/String"]
TFMessage = TS.types["tf2_msgs/msg/TFMessage"]
TransformStamped = TS.types["geometry_msgs/msg/TransformStamped"]
Transform = TS.types["geometry_msgs/msg/Transform"]
Vector3 = TS.types["geometry_msgs/msg/Vector3"]
Quaternion = TS.types["geometry_msgs/msg/Quaternion"]
T0 = 1_700_000_000_000_000_000
STORAGES = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}


def stamp(ns: int):
    return Time(*divmod(int(ns), 1_000_000_000))


def joint_state(stamp_ns: int, names: Sequence[str], position: Sequence[float], frame_id: str = "") -> bytes:
    msg = JointState(
        Header(stamp(stamp_ns), frame_id),
        list(names),
        np.asarray(position, dtype=np.float64),
        np.zeros(0),
        np.zeros(0),
    )
    return bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/JointState"))


def tf_message(items: Sequence[tuple[int, str, str, Sequence[float], Sequence[float]]]) -> bytes:
    """``(stamp ns, parent, child, xyz, quaternion xyzw)`` per transform."""
    transforms = [
        TransformStamped(Header(stamp(t), parent), child, Transform(Vector3(*xyz), Quaternion(*q)))
        for t, parent, child, xyz, q in items
    ]
    return bytes(TS.serialize_cdr(TFMessage(transforms), "tf2_msgs/msg/TFMessage"))


def string(text: str) -> bytes:
    return bytes(TS.serialize_cdr(String(text), "std_msgs/msg/String"))


TYPES = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/robot_description": "std_msgs/msg/String",
}


@dataclass
class BagSpec:
    messages: list[tuple[str, int, bytes]] = field(default_factory=list)  # (topic, receive ns, data)
    types: dict[str, str] = field(default_factory=lambda: dict(TYPES))

    def add(self, topic: str, receive_ns: int, data: bytes) -> BagSpec:
        self.messages.append((topic, receive_ns, data))
        return self


def write_bag(path: Path, spec: BagSpec, *, storage: str = "mcap", version: int = 9) -> Path:
    """A rosbag2 directory at ``path``; versions 1..7 are version 8 bags whose metadata.yaml is rewritten
    the way those versions wrote it (rosbags writes 8 and 9 only): the keys rosbag2 added in each version dropped
    (ros_distro in 8, type_description_hash in 7, custom_data in 6, files in 5, offered_qos_profiles in 4, the
    compression keys in 3), and before 4 the file paths written with the bag's folder in front."""
    with Writer(path, version=9 if version == 9 else 8, storage_plugin=STORAGES[storage]) as writer:
        connections = {}
        for topic, _, _ in spec.messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, spec.types[topic], typestore=TS)
        for topic, t, data in spec.messages:
            writer.write(connections[topic], t, data)
    if version < 8:
        meta = path / "metadata.yaml"
        yaml = YAML(typ="safe")
        info = yaml.load(meta.read_text())
        top = info["rosbag2_bagfile_information"]
        top["version"] = version
        top.pop("ros_distro", None)
        if version < 7:
            for topic in top["topics_with_message_count"]:
                topic["topic_metadata"].pop("type_description_hash", None)
        if version < 6:
            top.pop("custom_data", None)
        if version < 5:
            top.pop("files", None)
        if version < 4:
            top["relative_file_paths"] = [f"{path.name}/{name}" for name in top["relative_file_paths"]]
            for topic in top["topics_with_message_count"]:
                topic["topic_metadata"].pop("offered_qos_profiles", None)
        if version < 3:
            top.pop("compression_format", None)
            top.pop("compression_mode", None)
        with meta.open("w") as f:
            yaml.dump(info, f)
    return path


def storage_file(bag_dir: Path) -> Path:
    return next(p for p in bag_dir.iterdir() if p.suffix in (".mcap", ".db3"))


def unknown_type(bag_dir: Path, ros_type: str, unknown: str = "gz_msgs/msg/Link") -> None:
    """A db3 bag's topics of ``ros_type`` given a type nobody defines (``unknown``): the bag's definitions dropped,
    as a Gazebo bridge's bag without them, so nothing can decode those topics."""
    with sqlite3.connect(storage_file(bag_dir)) as db:
        db.execute("UPDATE topics SET type = ? WHERE type = ?", (unknown, ros_type))
        db.execute("DELETE FROM message_definitions")
    metadata = bag_dir / "metadata.yaml"
    metadata.write_text(metadata.read_text().replace(ros_type, unknown))


def write_split_bag(path: Path, parts: Sequence[BagSpec], *, storage: str = "mcap", metadata: bool = True) -> Path:
    """A bag of several storage files, as ``ros2 bag record --max-bag-duration`` splits one: each part written by
    rosbags as a bag of its own, its storage file moved into ``path`` as ``<path name>_<k>`` and, with ``metadata``,
    one metadata.yaml listing them all (rosbags' own, its file list and per-topic counts merged)."""
    path.mkdir()
    files: list[str] = []
    info: dict | None = None
    counts: dict[tuple[str, str], dict] = {}
    yaml = YAML(typ="safe")
    for k, part in enumerate(parts):
        single = write_bag(path.parent / f".{path.name}-part{k}", part, storage=storage)
        own = storage_file(single)
        name = f"{path.name}_{k}{own.suffix}"
        own.rename(path / name)
        files.append(name)
        top = yaml.load((single / "metadata.yaml").read_text())
        for topic in top["rosbag2_bagfile_information"]["topics_with_message_count"]:
            key = topic["topic_metadata"]["name"], topic["topic_metadata"]["type"]
            if key in counts:
                counts[key]["message_count"] += topic["message_count"]
            else:
                counts[key] = topic
        info = info or top
        (single / "metadata.yaml").unlink()
        single.rmdir()
    if metadata and info is not None:
        top = info["rosbag2_bagfile_information"]
        top["relative_file_paths"] = files
        top["files"] = [{"path": name} for name in files]
        top["topics_with_message_count"] = list(counts.values())
        top["message_count"] = sum(t["message_count"] for t in counts.values())
        with (path / "metadata.yaml").open("w") as f:
            yaml.dump(info, f)
    return path
