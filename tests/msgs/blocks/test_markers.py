"""MarkerArrays decoded a block at a time (issue 46, item 3): every field of every marker is what rosbags'
``deserialize_cdr`` (an independent deserialiser) reads from the same bytes — random markers of all twelve types
and the actions, both byte orders, empty and long strings, empty sequences, arrays that share a layout with other
values in it (same lengths, other bytes) — and messages the block cannot read are marked for the per-message path.

The messages are built and serialised by rosbags (``tests/msgs_build.py``)."""

from __future__ import annotations

import random
import struct
from typing import Any

import numpy as np
import pytest
from msgs_build import TS, T, color, duration, header, marker_msg, pose, quat, vec

from r2d2_viz.msgs.blocks.markers import MarkerBlock, decode_marker_arrays

ARRAY = "visualization_msgs/msg/MarkerArray"
TEXTS = ("", "a", "base_link", "/odom", "ünï ✓", "x" * 61)


def _random_marker(rng: random.Random, k: int) -> Any:
    def text() -> str:
        return rng.choice(TEXTS)

    def point() -> Any:
        return vec(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5), "Point")

    def rgba() -> Any:
        return color(rng.random(), rng.random(), rng.random(), rng.random())

    return marker_msg(
        rng.randint(0, 11),
        header=header(f"link{k % 10}", sec=rng.randint(-3, 3), nanosec=rng.randint(0, 999_999_999)),
        ns=text(),
        id=rng.randint(-(2**31), 2**31 - 1),
        action=rng.choice((0, 0, 0, 2, 3)),
        pose=pose(rng.random(), -rng.random(), k, quat(rng.random(), 0.0, rng.random(), rng.random())),
        scale=vec(rng.random(), rng.random(), rng.random()),
        color=rgba(),
        lifetime=duration(rng.randint(-2, 2), rng.randint(0, 999_999_999)),
        frame_locked=rng.random() < 0.5,
        points=[point() for _ in range(rng.choice((0, 1, 2, 5)))],
        colors=[rgba() for _ in range(rng.choice((0, 1, 3)))],
        texture_resource=text(),
        uv_coordinates=[T("visualization_msgs/msg/UVCoordinate")(u=0.5, v=0.25)] * rng.choice((0, 2)),
        text=text(),
        mesh_resource=text(),
        mesh_file=T("visualization_msgs/msg/MeshFile")(filename=text(), data=np.zeros(rng.choice((0, 7)), np.uint8)),
        mesh_use_embedded_materials=rng.random() < 0.5,
    )


def _messages() -> list[bytes]:
    """60 arrays: a third share one layout (frames of one length, other numbers), the rest random; every other
    one big-endian."""
    rng = random.Random(46)
    shared = [_random_marker(rng, 0) for _ in range(4)]
    out = []
    for k in range(60):
        if k % 3 == 0:
            markers = [
                marker_msg(m.type, **{f: getattr(m, f) for f in ("ns", "points", "colors", "text")}) for m in shared
            ]
            markers = [
                marker_msg(m.type, ns=m.ns, id=k, header=header(f"link{k % 10}", sec=k), pose=pose(k, -k, 0.5 * k))
                for m in shared
            ]
        else:
            markers = [_random_marker(rng, k) for _ in range(rng.choice((0, 1, 4)))]
        out.append(bytes(TS.serialize_cdr(T(ARRAY)(markers), ARRAY, little_endian=k % 2 == 0)))
    return out


def _expected(m: Any) -> dict[str, Any]:
    """One marker's fields as rosbags read them."""
    p, o = m.pose.position, m.pose.orientation
    return {
        "frame": m.header.frame_id,
        "stamp_ns": m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec,
        "ns": m.ns,
        "id": m.id,
        "type": m.type,
        "action": m.action,
        "pose": [p.x, p.y, p.z, o.x, o.y, o.z, o.w],
        "scale": [m.scale.x, m.scale.y, m.scale.z],
        "color": [m.color.r, m.color.g, m.color.b, m.color.a],
        "lifetime_ns": m.lifetime.sec * 1_000_000_000 + m.lifetime.nanosec,
        "frame_locked": bool(m.frame_locked),
        "points": [[q.x, q.y, q.z] for q in m.points],
        "colors": [[c.r, c.g, c.b, c.a] for c in m.colors],
        "text": m.text,
        "mesh_resource": m.mesh_resource,
        "embedded": bool(m.mesh_use_embedded_materials),
    }


def _got(b: MarkerBlock, j: int) -> dict[str, Any]:
    names = ("frame", "stamp_ns", "ns", "id", "type", "action", "lifetime_ns", "frame_locked", "text")
    out: dict[str, Any] = {
        name: getattr(b, name)[j].item() if name not in ("frame", "ns", "text") else getattr(b, name)[j]
        for name in names
    }
    out |= {"mesh_resource": b.mesh_resource[j], "embedded": bool(b.embedded[j])}
    out |= {"pose": b.pose[j].tolist(), "scale": b.scale[j].tolist(), "color": b.color[j].astype(float).tolist()}
    out["points"] = b.points[b.points_at[j] : b.points_at[j + 1]].tolist()
    out["colors"] = b.colors[b.colors_at[j] : b.colors_at[j + 1]].astype(float).tolist()
    return out


@pytest.fixture(scope="module")
def block() -> tuple[list[bytes], MarkerBlock]:
    messages = _messages()
    return messages, decode_marker_arrays(messages)


def test_every_field_is_what_rosbags_reads(block: tuple[list[bytes], MarkerBlock]) -> None:
    messages, b = block
    assert not b.bad.any()
    kinds = set()
    for i, data in enumerate(messages):
        markers = TS.deserialize_cdr(data, ARRAY).markers
        assert b.first[i + 1] - b.first[i] == len(markers)
        for j, m in zip(range(b.first[i], b.first[i + 1]), markers, strict=True):
            assert _got(b, j) == _expected(m), (i, j)
            kinds.add(m.type)
    assert kinds == set(range(12))
    assert b.first[-1] == len(b.id) > 100


def test_messages_it_cannot_read_are_left_to_the_per_message_path() -> None:
    good = bytes(TS.serialize_cdr(T(ARRAY)([marker_msg(1, ns="a", text="é")]), ARRAY))
    truncated = good[:-9]
    huge = good[:4] + struct.pack("<I", 2**31) + good[8:]
    not_utf8 = good.replace("é".encode(), b"\xff\xfe")
    xcdr2 = b"\x00\x07" + good[2:]
    b = decode_marker_arrays([good, truncated, huge, not_utf8, xcdr2, good, b"", b"\x00\x01"])
    assert b.bad.tolist() == [False, True, True, True, True, False, True, True]
    assert np.diff(b.first).tolist() == [1, 0, 0, 0, 0, 1, 0, 0]
    assert b.text.tolist() == ["é", "é"] and b.ns.tolist() == ["a", "a"]
    for data in (truncated, huge, not_utf8):  # and the per-message decoder says what is wrong
        with pytest.raises(Exception):  # noqa: B017  (rosbags' own errors)
            TS.deserialize_cdr(data, ARRAY)


def test_an_empty_window_and_empty_arrays() -> None:
    assert decode_marker_arrays([]).first.tolist() == [0]
    empty = bytes(TS.serialize_cdr(T(ARRAY)([]), ARRAY))
    b = decode_marker_arrays([empty, empty])
    assert b.first.tolist() == [0, 0, 0] and not b.bad.any() and b.points.shape == (0, 3)


def test_a_seeded_fuzz_reads_what_rosbags_reads_and_leaves_what_it_refuses() -> None:
    """Truncations, flipped bytes and huge lengths: nothing raises; a message rosbags cannot read is left to the
    per-message path (which says why); one it reads has its values."""
    rng = random.Random(4646)
    base = _messages()[1:9]
    fuzzed = []
    for k in range(300):
        data = bytearray(base[k % len(base)])
        if k % 3 == 0:
            data = data[: rng.randrange(len(data))]
        elif k % 3 == 1:
            for _ in range(rng.randint(1, 4)):
                data[rng.randrange(4, len(data))] = rng.randrange(256)
        else:
            at = rng.randrange(4, max(5, len(data) - 4)) & ~3
            data[at : at + 4] = struct.pack("<I", rng.choice((2**31, 2**32 - 1, 1 << 20)))
        fuzzed.append(bytes(data))
    b = decode_marker_arrays(fuzzed)
    read = 0
    for i, data in enumerate(fuzzed):
        try:
            markers = TS.deserialize_cdr(data, ARRAY).markers
        except Exception as exc:  # rosbags refuses it: so must the block
            assert b.bad[i], (i, exc)
            continue
        if b.bad[i]:
            continue  # (a message rosbags reads by luck, e.g. bytes that are no UTF-8: decoded alone, as today)
        read += 1
        assert b.first[i + 1] - b.first[i] == len(markers)
        for j, m in zip(range(b.first[i], b.first[i + 1]), markers, strict=True):
            got, expected = _got(b, j), _expected(m)
            assert str(sorted(got.items())) == str(sorted(expected.items())), (i, j)  # (str: NaN equals NaN)
    assert read > 50
