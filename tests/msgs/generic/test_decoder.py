"""Every topic of the real bags (tests/data/bags/real, or ../shared/bags/real; skipped when absent) decoded field
by field as the recording gets it, against rosbags' own reader and deserializer (AnyReader, Humble's types): every
field name and value of every message of every topic our pass decodes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fieldbags import expected_fields
from msgs.test_real_bags import BAGS, TYPESTORE, bag_dir
from rosbags.highlevel import AnyReader

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.fields_pass import FieldsPass

OURS = {"/tf", "/tf_static", "/joint_states", "/robot_description"}


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    x, y = np.float64(a), np.float64(b)
    return bool(x == y or (np.isnan(x) and np.isnan(y)))


ROS1 = Path(__file__).resolve().parents[2] / "data" / "bags" / "ros1" / "example-lz4.bag"


@pytest.mark.parametrize("name", [*sorted(BAGS), "ros1"])
def test_every_field_of_every_topic_is_what_rosbags_reads(name: str) -> None:
    """The ROS 1 bag (turtlesim's own types, defined only in the bag's connection headers): rosbags' ROS 1 reader."""
    path = ROS1 if name == "ros1" else bag_dir(name)
    with open_bag(path, warn=lambda _: None) as bag:
        fields = FieldsPass(bag, {t: i.msgtype for t, i in bag.topics.items() if t not in OURS})
        got: dict[str, list[tuple[int, dict[str, Any]]]] = {}
        for block in bag.blocks(fields.topics):
            for topic, columns in fields.decode(block):
                for i, t in enumerate(columns.times_ns):
                    row = {k: v[i] for k, v in (*columns.numbers.items(), *columns.texts.items())}
                    got.setdefault(topic, []).append((int(t), row))
    assert fields.topics, fields.unusable
    with AnyReader([path], default_typestore=None if name == "ros1" else TYPESTORE) as reader:
        store = reader.typestore
        connections = [c for c in reader.connections if c.topic in fields.topics]
        want: dict[str, list[tuple[int, dict[str, Any]]]] = {}
        for c, t, raw in reader.messages(connections=connections):
            msg = reader.deserialize(raw, c.msgtype)
            golden = expected_fields(store, msg, c.msgtype)
            if name == "ros1":  # ROS 1's Header.seq: given for the message's own header (read beside its bytes)
                golden = {k: v for k, v in golden.items() if not k.endswith(".header.seq")}  # not for nested ones
            want.setdefault(c.topic, []).append((t, golden))
    assert set(got) == set(want)
    for topic in want:
        mine = sorted(got[topic], key=lambda r: r[0])
        theirs = sorted(want[topic], key=lambda r: r[0])
        assert [t for t, _ in mine] == [t for t, _ in theirs], topic
        for (t, row), (_, golden) in zip(mine, theirs, strict=True):
            golden = {
                k: v
                for k, v in golden.items()
                if not (k.endswith((".min", ".max")) and golden.get(k[:-4] + ".len") == 0)
            }
            row = {k: v for k, v in row.items() if k in golden or not k.endswith((".min", ".max"))}
            assert set(row) == set(golden), (topic, t, set(row) ^ set(golden))
            bad = [k for k in golden if not _same(row[k], golden[k])]
            assert not bad, (topic, t, [(k, row[k], golden[k]) for k in bad[:5]])
