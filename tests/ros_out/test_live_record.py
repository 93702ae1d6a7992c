"""``--ros --save out.mcap``: what came, as it came, read back by rosbags with each topic's type."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader

from r2d2_viz.errors import BagError
from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.ros_out.live_record import LiveBagRecorder
from r2d2_viz.sources.live.dds import Sample


def test_samples_recorded_byte_for_byte(tmp_path: Path) -> None:
    store = typestore("jazzy")
    text = bytes(store.serialize_cdr(store.types["std_msgs/msg/String"](data="<robot/>"), "std_msgs/msg/String"))
    samples = [
        Sample("/robot_description", "std_msgs/msg/String", 1_000, text),
        Sample("/chatter", "std_msgs/msg/String", 2_000, text),
        Sample("/joint_states", "sensor_msgs/msg/JointState", 3_000, b"\x00\x01\x00\x00garbage!"),
    ]
    path = tmp_path / "out.mcap"
    with LiveBagRecorder(path) as bag:
        bag.write(samples)
    assert (path / "metadata.yaml").is_file() and not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    with AnyReader([path], default_typestore=store) as reader:
        got = [(c.topic, c.msgtype, t, bytes(raw)) for c, t, raw in reader.messages()]
        latched = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
    assert got == [(s.topic, s.ros_type, s.source_timestamp_ns, s.data) for s in samples]
    assert "transient_local" in str(latched["/robot_description"]).lower()


def test_an_aborted_bag_leaves_nothing_and_a_file_is_not_overwritten(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError), LiveBagRecorder(tmp_path / "out.mcap"):
        raise RuntimeError
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "x.mcap").write_text("mine")
    with pytest.raises(BagError, match="not overwriting"):
        LiveBagRecorder(tmp_path / "x.mcap")
