"""Any message's fields decoded as numpy columns (r2d2_viz.msgs.generic.fields, field_decoder) against rosbags' own
deserializer, message by message: every field name, every value (the golden source is rosbags' dataclasses, read
by attribute here)."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pytest
from fieldbags import BATTERY, STATE, expected_fields, messages, store

from r2d2_viz.msgs.generic.decoder import FieldDecoder

TS = store()


def decoded(topic: str, msgtype: str, data: list[bytes], decoder: FieldDecoder | None = None) -> list[dict[str, Any]]:
    """Each message's fields as decoded by the code under test (all messages handed over at once)."""
    decoder = decoder or FieldDecoder(TS, msgtype)
    buf = np.frombuffer(b"".join(data), dtype=np.uint8)
    lengths = np.array([len(d) for d in data], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    rows: list[dict[str, Any]] = [{} for _ in data]
    for columns in decoder.decode(buf, starts, lengths, np.arange(len(data), dtype=np.int64)):
        for name, values in (*columns.numbers.items(), *columns.texts.items()):
            for t, v in zip(columns.times_ns, values, strict=True):
                rows[int(t)][name] = v
    return rows


def _same(a: Any, b: Any) -> bool:
    if isinstance(b, str) or isinstance(a, str):
        return a == b
    return bool(np.float64(a) == np.float64(b)) or (np.isnan(np.float64(a)) and np.isnan(np.float64(b)))


@pytest.mark.parametrize(
    ("topic", "msgtype"), [("/battery", BATTERY), ("/arm_controller/state", STATE), ("/odom", "nav_msgs/msg/Odometry")]
)
def test_every_field_of_every_message_is_what_rosbags_decodes(topic: str, msgtype: str) -> None:
    data = [d for t, _, d in messages(400) if t == topic]
    got = decoded(topic, msgtype, data)
    for k, (raw, fields) in enumerate(zip(data, got, strict=True)):
        want = expected_fields(TS, TS.deserialize_cdr(raw, msgtype), msgtype)
        if "blob.len" in want and not want["blob.len"]:  # an empty blob: its length, no min or max
            fields = {n: v for n, v in fields.items() if n not in ("blob.min", "blob.max")}
        assert set(fields) == set(want), (k, set(fields) ^ set(want))
        bad = [n for n in want if not _same(fields[n], want[n])]
        assert not bad, (k, [(n, fields[n], want[n]) for n in bad])


def test_layouts_are_matched_not_walked_message_by_message() -> None:
    """400 odometry messages of one layout: one walk, the rest matched by numpy (the speed goal's mechanism)."""
    data = [d for t, _, d in messages(400) if t == "/odom"]
    decoder = FieldDecoder(TS, "nav_msgs/msg/Odometry")
    walks = 0
    import r2d2_viz.msgs.generic.decoder as fd

    real = fd.walk

    def counted(*args: Any, **kwargs: Any) -> Any:
        nonlocal walks
        walks += 1
        return real(*args, **kwargs)

    fd.walk = counted  # type: ignore[assignment]
    try:
        decoded("/odom", "nav_msgs/msg/Odometry", data, decoder)
        decoded("/odom", "nav_msgs/msg/Odometry", data, decoder)  # the next window: the known layout, no walk
    finally:
        fd.walk = real
    assert walks == 1 and decoder.decoded == 800


def test_wanted_fields_only() -> None:
    data = [d for t, _, d in messages(20) if t == "/arm_controller/state"]
    decoder = FieldDecoder(TS, STATE, frozenset({"error.positions[0]"}))
    [row, *_] = decoded("/arm_controller/state", STATE, data, decoder)
    assert set(row) == {"error.positions[0]"}


def _odom(k: int) -> bytes:
    return [d for t, _, d in messages(k + 1) if t == "/odom"][k]


def test_bad_messages_are_counted_and_the_rest_decoded() -> None:
    """Shorter than its definition, an array length field of 2**31, NaN and infinity, a string not UTF-8."""
    good = [_odom(k) for k in range(3)]
    short = good[0][:40]
    huge = bytearray(good[1])
    frame = re.search(rb"base_link\x00", huge)
    assert frame is not None
    huge[frame.start() - 4 : frame.start()] = (1 << 31).to_bytes(4, "little")  # header.frame_id's length
    nan = bytearray(good[2])
    nan[-8:] = np.float64(np.inf).tobytes()  # the last covariance entry
    latin = bytearray(good[2])
    latin[frame.start()] = 0xE9  # "\xe9ase_link": not UTF-8
    decoder = FieldDecoder(TS, "nav_msgs/msg/Odometry")
    rows = decoded("/odom", "nav_msgs/msg/Odometry", [good[0], short, bytes(huge), bytes(nan), bytes(latin)], decoder)
    assert rows[1] == {} and rows[2] == {}
    assert rows[3]["twist.covariance[35]"] == np.inf and rows[4]["header.frame_id"] == "\ufffdase_link"
    assert rows[0]["pose.pose.position.x"] == 0.0
    lines = decoder.problems.lines()
    assert "1 message skipped: shorter than its definition (a length field of 10)" in lines, lines  # cut in frame_id
    assert "1 message skipped: shorter than its definition (a length field of 2147483648)" in lines, lines
    assert "1 message with NaN or infinity in a field" in lines and "1 string not UTF-8 (shown with U+FFFD)" in lines


def test_an_array_length_field_of_2_to_the_31_skips_that_message_only() -> None:
    data = [d for t, _, d in messages(3) if t == "/arm_controller/state"]
    names = b"\x03\x00\x00\x00\x0d\x00\x00\x00panda_joint1\x00"  # joint_names: 3 strings, the first 13 bytes
    assert names in data[1]
    data[1] = data[1].replace(names, (1 << 31).to_bytes(4, "little") + names[4:])
    decoder = FieldDecoder(TS, STATE)
    rows = decoded("/arm_controller/state", STATE, data, decoder)
    assert rows[1] == {} and rows[2]["joint_names[2]"] == "panda_joint3" and rows[0]["error.positions[2]"] == 0.05
    assert decoder.problems.lines() == ["1 message skipped: shorter than its definition (a length field of 2147483648)"]


def test_named_items_of_summarised_arrays_are_read_the_rest_summarised() -> None:
    """`keep`: the items a path names, read whatever the summary; golden values from rosbags' deserializer."""
    data = [d for t, _, d in messages(40) if t == "/battery"]
    keep = frozenset({"blob[5]", "blob[-1]", "cells[-1].charge", "events[-1]"})
    got = decoded("/battery", BATTERY, data, FieldDecoder(TS, BATTERY, None, keep))
    for raw, fields in zip(data, got, strict=True):
        msg = TS.deserialize_cdr(raw, BATTERY)
        want = {"blob[5]": msg.blob[5] if len(msg.blob) > 5 else None}
        want |= {"blob[-1]": msg.blob[-1] if len(msg.blob) else None}
        want |= {"cells[-1].charge": msg.cells[-1].charge if msg.cells else None}
        want |= {"events[-1]": msg.events[-1] if len(msg.events) else None}
        for name, value in want.items():
            assert fields.get(name) == value, (name, fields.get(name), value)
        assert "blob.len" in fields  # the summary stays


def test_a_message_longer_than_its_definition_is_a_size_mismatch() -> None:
    from r2d2_viz.msgs.generic.fields import walk

    raw = bytes(TS.serialize_cdr(TS.deserialize_cdr(messages(1)[0][2], BATTERY), BATTERY))
    walk(TS, BATTERY, raw + b"\0\0\0")  # CDR's padding: fine (as rosbags)
    with pytest.raises(ValueError, match="size mismatch"):
        walk(TS, BATTERY, raw + b"\0" * 4)
