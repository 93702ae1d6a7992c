"""ROS 1 bags whose ``header.seq`` has known gaps, written with rosbags' ROS 1 writer and ``serialize_ros1`` (Noetic
definitions): ``/temp`` (``sensor_msgs/Temperature``, one publisher) at 10 Hz for 4 s with the messages of
:data:`DROPPED` slots missing; ``/pair`` (the same type, two publishers each counting its own ``seq``); ``/value``
(``std_msgs/Float64``, no header); ``/ref`` (``sensor_msgs/TimeReference``, which no display draws: its fields are
shown) with seq :data:`REF_SEQ`."""

from __future__ import annotations

from pathlib import Path

from rosbags.rosbag1 import Reader, Writer
from rosbags.typesys import Stores, get_typestore

NOETIC = get_typestore(Stores.ROS1_NOETIC)
T0 = 1_700_000_000 * 10**9
MS = 1_000_000
SLOTS = 40
DROPPED = (5, 6, 7, 20)
"""Slots (100 ms apart) whose ``/temp`` message never reached the recorder: 4 missing seq numbers, by hand."""
FIRST_SEQ = 100
TEMP = "sensor_msgs/msg/Temperature"
REF = "sensor_msgs/msg/TimeReference"
REF_SEQ = (0, 1, 2, 4, 5, 9, 10)
"""3, 6, 7 and 8 missing: 4 drops, by hand."""


def _temperature(seq: int, k: int) -> bytes:
    T = NOETIC.types
    stamp = T["builtin_interfaces/msg/Time"](sec=T0 // 10**9, nanosec=k * 100 * MS)
    header = T["std_msgs/msg/Header"](seq=seq, stamp=stamp, frame_id="probe")
    return bytes(NOETIC.serialize_ros1(T[TEMP](header=header, temperature=20.0 + k, variance=0.5), TEMP))


def _time_reference(seq: int, k: int) -> bytes:
    T = NOETIC.types
    stamp = T["builtin_interfaces/msg/Time"](sec=T0 // 10**9 + k, nanosec=0)
    header = T["std_msgs/msg/Header"](seq=seq, stamp=stamp, frame_id="gps")
    return bytes(NOETIC.serialize_ros1(T[REF](header=header, time_ref=stamp, source="gps"), REF))


def write(path: Path) -> Path:
    writer = Writer(path)
    writer.chunk_threshold = 2000  # several chunks: seq read across chunk boundaries
    with writer:
        temp = writer.add_connection("/temp", TEMP, typestore=NOETIC)
        pair = [writer.add_connection("/pair", TEMP, typestore=NOETIC, callerid=f"/n{i}") for i in range(2)]
        value = writer.add_connection("/value", "std_msgs/msg/Float64", typestore=NOETIC)
        ref = writer.add_connection("/ref", REF, typestore=NOETIC)
        f64 = NOETIC.types["std_msgs/msg/Float64"]
        for k in range(SLOTS):
            t = T0 + k * 100 * MS
            if k not in DROPPED:
                writer.write(temp, t, _temperature(FIRST_SEQ + k, k))
            writer.write(pair[k % 2], t + 1, _temperature(k // 2, k))  # each publisher's own count: 0, 0, 1, 1 ...
            writer.write(value, t + 2, bytes(NOETIC.serialize_ros1(f64(data=float(k)), "std_msgs/msg/Float64")))
            if k < len(REF_SEQ):
                writer.write(ref, t + 3, _time_reference(REF_SEQ[k], k))
    return path


def seqs(path: Path, topic: str) -> list[tuple[int, int]]:
    """``(receive time, header.seq)`` of ``topic``'s messages, as rosbags' own ROS 1 reader and deserialiser give."""
    with Reader(path) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        return [(t, NOETIC.deserialize_ros1(d, c.msgtype).header.seq) for c, t, d in reader.messages(connections=conns)]


CLOCK = "rosgraph_msgs/msg/Clock"
CLOCK_MESSAGES = 101
"""``/clock`` every 100 ms for 10 s: a ROS 1 ``time`` of 8 bytes each (its CDR, 4 bytes of encapsulation more, 12)."""


def write_clock(path: Path) -> Path:
    """A ROS 1 bag of :data:`CLOCK_MESSAGES` ``rosgraph_msgs/Clock`` on ``/clock``, 100 ms apart (rosbags' writer)."""
    T = NOETIC.types
    with Writer(path) as writer:
        clock = writer.add_connection("/clock", CLOCK, typestore=NOETIC)
        for k in range(CLOCK_MESSAGES):
            now = T["builtin_interfaces/msg/Time"](sec=k // 10, nanosec=k % 10 * 100 * MS)
            writer.write(clock, T0 + k * 100 * MS, bytes(NOETIC.serialize_ros1(T[CLOCK](clock=now), CLOCK)))
    return path
