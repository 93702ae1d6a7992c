"""Crafted bags for the TF tree (written by rosbags through tests/bagmaker.py) and the reference the tests hold
our analysis to: every edge's receive times read back with rosbags' own reader and deserialiser, so that rates,
edges and gaps come from rosbags, not from r2d2_viz."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from bagmaker import T0, TS, TYPES, BagSpec, Header, joint_state, stamp, string, tf_message, write_bag
from rosbags.highlevel import AnyReader

POINT = "geometry_msgs/msg/PointStamped"
PointStamped = TS.types[POINT]
Point = TS.types["geometry_msgs/msg/Point"]
MS = 1_000_000
S = 1_000_000_000
Q = (0.0, 0.0, 0.0, 1.0)


def point(stamp_ns: int, frame: str) -> bytes:
    return bytes(TS.serialize_cdr(PointStamped(Header(stamp(stamp_ns), frame), Point(1.0, 2.0, 3.0)), POINT))


def spec() -> BagSpec:
    s = BagSpec()
    s.types["/points"] = POINT
    return s


def edge_every(s: BagSpec, parent: str, child: str, times_ns: Sequence[int], lag_ns: int = 0) -> BagSpec:
    """One /tf message per time, received then, stamped ``lag_ns`` earlier."""
    for t in times_ns:
        s.add("/tf", int(t), tf_message([(int(t) - lag_ns, parent, child, (1.0, 0.0, 0.0), Q)]))
    return s


def static(s: BagSpec, edges: Sequence[tuple[str, str]]) -> BagSpec:
    return s.add("/tf_static", T0, tf_message([(T0, p, c, (0.0, 0.0, 0.1), Q) for p, c in edges]))


def bag(path: Path, s: BagSpec, storage: str = "mcap") -> Path:
    s.messages.sort(key=lambda m: m[1])
    return write_bag(path, s, storage=storage)


def reference_edges(path: Path) -> dict[tuple[str, str], list[int]]:
    """``(parent, child)`` → the receive times of its /tf messages, read with rosbags (leading '/' dropped)."""
    out: dict[tuple[str, str], list[int]] = {}
    with AnyReader([path], default_typestore=TS) as reader:
        conns = [c for c in reader.connections if c.topic == "/tf"]
        for conn, t, data in reader.messages(connections=conns):
            msg = reader.deserialize(data, conn.msgtype)
            for tr in msg.transforms:
                edge = (tr.header.frame_id.lstrip("/"), tr.child_frame_id.lstrip("/"))
                out.setdefault(edge, []).append(t)
    return out


def reference_static(path: Path) -> set[tuple[str, str]]:
    with AnyReader([path], default_typestore=TS) as reader:
        conns = [c for c in reader.connections if c.topic == "/tf_static"]
        return {
            (tr.header.frame_id.lstrip("/"), tr.child_frame_id.lstrip("/"))
            for conn, _, data in reader.messages(connections=conns)
            for tr in reader.deserialize(data, conn.msgtype).transforms
        }


def rate_and_gap(times: list[int]) -> tuple[float, float]:
    """messages − 1 over the span (Hz), and the largest gap (s)."""
    t = np.sort(np.asarray(times, dtype=np.int64))
    return (len(t) - 1) / ((t[-1] - t[0]) / S), float(np.diff(t).max()) / S


ROVER = """<robot name="rover"><link name="base_link"/><link name="laser"/><link name="wheel"/><link name="wheel2"/>
<link name="caster"/>
<joint name="laser_mount" type="fixed"><parent link="base_link"/><child link="laser"/><origin xyz="0.1 0 0.2"/></joint>
<joint name="wheel_joint" type="continuous"><parent link="base_link"/><child link="wheel"/><axis xyz="0 1 0"/></joint>
<joint name="wheel2_joint" type="continuous"><parent link="base_link"/><child link="wheel2"/><axis xyz="0 1 0"/>
<mimic joint="wheel_joint"/></joint>
<joint name="caster_joint" type="continuous"><parent link="base_link"/><child link="caster"/></joint></robot>"""
"""A robot as robot_state_publisher sees it: ``laser`` on a fixed joint (``/tf_static``), ``wheel`` moved by the
joint states, ``wheel2`` mimicking it (published with it), ``caster`` never named by a joint state (never published)."""


def rover(s: BagSpec, times_ns: Sequence[int], namespace: str = "") -> BagSpec:
    """``<namespace>/robot_description`` (:data:`ROVER`) and its joint states naming ``wheel_joint`` at ``times_ns``."""
    s.types[f"{namespace}/robot_description"] = TYPES["/robot_description"]
    s.types[f"{namespace}/joint_states"] = TYPES["/joint_states"]
    s.add(f"{namespace}/robot_description", T0, string(ROVER))
    for k, t in enumerate(times_ns):
        s.add(f"{namespace}/joint_states", int(t), joint_state(int(t), ["wheel_joint"], [0.1 * k]))
    return s


def receive_times(path: Path, topic: str) -> list[int]:
    """The receive times of ``topic``'s messages, read with rosbags."""
    with AnyReader([path], default_typestore=TS) as reader:
        return [t for _, t, _ in reader.messages(connections=[c for c in reader.connections if c.topic == topic])]


def real_bag(name: str) -> Path:
    """A third-party bag of tests/data/bags/real/README.md, where a clone or the developers keep it; skips without."""
    import pytest

    repo = Path(__file__).resolve().parents[1]
    for place in (repo / "tests" / "data" / "bags" / "real", repo.parent / "shared" / "bags" / "real"):
        if (place / name / "metadata.yaml").is_file():
            return place / name
    pytest.skip(
        f"the third-party bag {name} is not in this clone: put its files in tests/data/bags/real/{name}/ "
        "(tests/data/bags/real/README.md says where it comes from)"
    )
