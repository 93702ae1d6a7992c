"""Each topic's rate and bandwidth over a bag (``--list``), held to the same computed from rosbags' own reader:
its receive times and the sizes of the raw messages it hands out."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from rosbags.highlevel import AnyReader
from tfbags import MS, T0, TS, bag, edge_every, point, real_bag, spec

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.system.topic_rates import TopicRate, rate_words, si, topic_rates


def reference(path: Path) -> dict[str, tuple[int, int, int, int]]:
    """topic → (count, bytes, first, last) by rosbags."""
    out: dict[str, list[int]] = {}
    with AnyReader([path], default_typestore=TS) as reader:
        for conn, t, data in reader.messages():
            got = out.setdefault(conn.topic, [0, 0, t, t])
            got[0] += 1
            got[1] += len(data)
            got[2], got[3] = min(got[2], t), max(got[3], t)
    return {k: (v[0], v[1], v[2], v[3]) for k, v in out.items()}


def ours(path: Path) -> dict[str, tuple[int, int, int, int]]:
    with open_bag(path) as b:
        return {t: (r.count, r.nbytes, r.first_ns, r.last_ns) for t, r in topic_rates(b).items()}


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_counts_bytes_and_spans_agree_with_rosbags(tmp_path: Path, storage: str) -> None:
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(50) * 20 * MS)
    for k in range(30):
        s.add("/points", T0 + k * 33 * MS, point(T0, "camera" * (k % 4)))
    path = bag(tmp_path / "b", s, storage)
    assert ours(path) == reference(path)


def test_a_real_bag_agrees_with_rosbags() -> None:
    path = real_bag("webots_epuck")
    expected = reference(path)
    assert len(expected) > 20 and ours(path) == expected


def test_words() -> None:
    # by hand: 11 messages over 1 s → 10 Hz; 3,300 bytes over 1 s
    assert rate_words(TopicRate(11, 3300, 0, 1_000_000_000)) == ", 10 Hz, 3.3 kB/s"
    assert rate_words(TopicRate(1, 100, 5, 5)) == "" and rate_words(None) == ""
    assert si(2.5e6, "B/s") == "2.5 MB/s" and si(0.346, "Hz") == "0.346 Hz"


def test_list_prints_rate_and_bandwidth(tmp_path: Path) -> None:
    s = spec()
    edge_every(s, "map", "odom", T0 + np.arange(21) * 50 * MS)  # 21 messages over 1 s: 20 Hz
    s.add("/points", T0, point(T0, "camera"))
    path = bag(tmp_path / "b", s)
    done = cli("--bag", str(path), "--list")
    assert done.returncode == 0, done.stderr
    size = reference(path)["/tf"][1]  # bytes as rosbags hands them out, over the same 1 s
    assert done.stdout.splitlines() == [
        "/points [geometry_msgs/msg/PointStamped] 1 message",
        f"/tf [tf2_msgs/msg/TFMessage] 21 messages, 20 Hz, {si(size, 'B/s')}",
    ]


def test_ros1_drops_from_seq_gaps(tmp_path: Path) -> None:
    """A ROS 1 bag written with rosbags whose ``/temp`` lost 4 messages (``/ref``: 4 seq numbers skipped): the drops
    are the seq numbers missing between the messages rosbags deserialises; unknown (None) without a header
    (``/value``) and with two publishers each counting its own (``/pair``)."""
    from seqbags import DROPPED, REF_SEQ, seqs, write

    path = write(tmp_path / "seq.bag")
    with open_bag(path) as b:
        rates = topic_rates(b)
    for topic in ("/temp", "/ref"):
        got = [s for _, s in seqs(path, topic)]
        assert rates[topic].drops == sum(b - a - 1 for a, b in itertools.pairwise(got))
    assert rates["/temp"].drops == len(DROPPED) and rates["/ref"].drops == 4 == REF_SEQ[-1] + 1 - len(REF_SEQ)
    assert rates["/value"].drops is None and rates["/pair"].drops is None


def test_list_says_ros1_drops(tmp_path: Path) -> None:
    from seqbags import write

    done = cli("--bag", str(write(tmp_path / "seq.bag")), "--list")
    assert done.returncode == 0, done.stderr
    lines = {line.split(" ")[0]: line for line in done.stdout.splitlines()}
    assert lines["/temp"].endswith(", 4 dropped") and lines["/ref"].endswith(", 4 dropped")
    assert "dropped" not in lines["/value"] + lines["/pair"]
    assert rate_words(TopicRate(11, 3300, 0, 1_000_000_000, 2)) == ", 10 Hz, 3.3 kB/s, 2 dropped"
    assert rate_words(TopicRate(1, 100, 5, 5, 0)) == ", 0 dropped"


def test_the_real_turtlesim_rosout_has_no_drops_to_speak_of() -> None:
    """The real ROS 1 bag's ``/rosout`` holds several nodes' messages on one connection: its seq goes back (rosbags
    deserialises 3..10, then 2, 0), so no drops are claimed."""
    from seqbags import seqs

    path = Path(__file__).parents[2] / "data/bags/ros1/example-lz4.bag"
    got = [s for _, s in seqs(path, "/rosout")]
    assert any(b <= a for a, b in itertools.pairwise(got))
    with open_bag(path) as b:
        assert topic_rates(b)["/rosout"].drops is None


def ros1_reference(path: Path) -> dict[str, tuple[int, int, int, int]]:
    """topic → (count, bytes, first, last) by rosbags' own ROS 1 reader: the raw (ROS 1 serialised) messages."""
    from rosbags.rosbag1 import Reader

    out: dict[str, list[int]] = {}
    with Reader(path) as reader:
        for conn, t, data in reader.messages():
            got = out.setdefault("/" + conn.topic.lstrip("/"), [0, 0, t, t])
            got[0] += 1
            got[1] += len(data)
            got[2], got[3] = min(got[2], t), max(got[3], t)
    return {k: (v[0], v[1], v[2], v[3]) for k, v in out.items()}


def test_ros1_bytes_are_the_bags_own(tmp_path: Path) -> None:
    """A ROS 1 topic's bytes are its messages as the bag stores them (ROS 1 serialised), not their conversion to
    CDR: every topic of the real turtlesim bag and of two bags written with rosbags agrees with rosbags' ROS 1
    reader; ``/clock`` by hand: 101 messages of 8 bytes over 10 s, 80.8 B/s (its CDR would be 12 bytes each)."""
    from seqbags import write, write_clock

    real = Path(__file__).parents[2] / "data/bags/ros1/example-lz4.bag"
    for path in (real, write(tmp_path / "seq.bag"), write_clock(tmp_path / "clock.bag")):
        expected = ros1_reference(path)
        assert len(expected) >= 2 or path.name == "clock.bag"
        assert ours(path) == expected
    with open_bag(tmp_path / "clock.bag") as b:
        clock = topic_rates(b)["/clock"]
    assert (clock.count, clock.nbytes, clock.bandwidth) == (101, 808, pytest.approx(80.8))
    # the same bag cut after its one chunk, before the chunk's index records (a killed recorder): read by a scan
    data = (tmp_path / "clock.bag").read_bytes()
    records, at = [], 13  # after '#ROSBAG V2.0\n': header length, header, data length, data
    while at < len(data):
        header = int.from_bytes(data[at : at + 4], "little")
        at += 8 + header + int.from_bytes(data[at + 4 + header : at + 8 + header], "little")
        records.append(at)
    (tmp_path / "cut.bag").write_bytes(data[: records[1]])  # the bag header, the chunk
    assert ours(tmp_path / "cut.bag") == ros1_reference(tmp_path / "clock.bag")
    done = cli("--bag", str(tmp_path / "clock.bag"), "--list")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["/clock [rosgraph_msgs/msg/Clock] 101 messages, 10 Hz, 80.8 B/s"]


def test_a_layout_converted_to_humbles_counts_the_bags_own_bytes(tmp_path: Path) -> None:
    """``/temp`` whose bag defines ``sensor_msgs/msg/Temperature`` with a field Humble's lacks (a 40-character
    ``note``): its messages are converted to Humble's layout to be read, but its bytes are the bag's own, as
    rosbags' reader hands them out (979 over 1 s; converted, 484)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register({k: TS.fielddefs[k] for k in ("std_msgs/msg/Header", "builtin_interfaces/msg/Time")})
    text = "std_msgs/Header header\nfloat64 temperature\nfloat64 variance\nstring note\n"
    store.register(get_types_from_msg(text, "sensor_msgs/msg/Temperature"))
    temp = store.types["sensor_msgs/msg/Temperature"]
    header, time = store.types["std_msgs/msg/Header"], store.types["builtin_interfaces/msg/Time"]
    path = tmp_path / "b"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/temp", "sensor_msgs/msg/Temperature", typestore=store)
        for k in range(11):
            msg = temp(header(time(T0 // 1_000_000_000, k * 100 * MS), "probe"), 20.0, 0.5, "x" * 40)
            writer.write(conn, T0 + k * 100 * MS, bytes(store.serialize_cdr(msg, "sensor_msgs/msg/Temperature")))
    with open_bag(path) as b:
        assert b.humble_topics == {"/temp"}  # converted to be read
    assert ours(path) == reference(path) and reference(path)["/temp"][1] == 979
