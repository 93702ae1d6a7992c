"""ROS 1 bags (rosbag v2.0) read without ROS: bags written here with rosbags' ROS 1 writer (each compression, several
connections on one topic, names without a slash, a pre-2010 ``roslib/Header``), damaged (no index, cut anywhere),
and their messages compared, as CDR decoded with Humble's store, with the values written."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.rosbag1 import Writer
from rosbags.typesys import Stores, get_typestore

from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.sources.bags.rosbag1 import Rosbag1

NOETIC = get_typestore(Stores.ROS1_NOETIC)
T0 = 1_700_000_000 * 10**9
SEP = "=" * 80 + "\n"
TF_DEF = (
    "geometry_msgs/TransformStamped[] transforms\n"
    + SEP
    + "MSG: geometry_msgs/TransformStamped\n"
    + NOETIC.generate_msgdef("geometry_msgs/msg/TransformStamped")[0]
)
"""tf/tfMessage, which rosbags' Noetic store lacks: its definition as rosbag writes it."""


def _header(sec: int, frame: str, seq: int = 7) -> Any:
    time = NOETIC.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=5)
    return NOETIC.types["std_msgs/msg/Header"](seq=seq, stamp=time, frame_id=frame)


def _joint_state(k: int, names: list[str] | None = None) -> bytes:
    names = ["a", "b"] if names is None else names
    msg = NOETIC.types["sensor_msgs/msg/JointState"](
        header=_header(k, "base"),
        name=names,
        position=np.arange(len(names), dtype=np.float64) + k,
        velocity=np.zeros(0),
        effort=np.zeros(0),
    )
    return bytes(NOETIC.serialize_ros1(msg, "sensor_msgs/msg/JointState"))


def _tf(k: int, child: str) -> bytes:
    """A tf/tfMessage, serialised by hand (ROS 1: little endian, no alignment)."""
    header = struct.pack("<III", 0, k, 5) + struct.pack("<I", 4) + b"odom"
    one = header + struct.pack("<I", len(child)) + child.encode() + struct.pack("<7d", k, 2, 3, 0, 0, 0, 1)
    return struct.pack("<I", 1) + one


def _write(path: Path, compression: str = "none", n: int = 300, threshold: int = 4000) -> Path:
    writer = Writer(path)
    if compression != "none":
        writer.set_compression(getattr(writer.CompressionFormat, compression.upper()))
    writer.chunk_threshold = threshold
    with writer:
        js = writer.add_connection("joint_states", "sensor_msgs/msg/JointState", typestore=NOETIC)
        tfa = writer.add_connection("/tf", "tf/msg/tfMessage", msgdef=TF_DEF, md5sum="94810edda583a504dfda3829e70d7eec",
                                    callerid="/a")  # fmt: skip
        tfb = writer.add_connection("/tf", "tf/msg/tfMessage", msgdef=TF_DEF, md5sum="94810edda583a504dfda3829e70d7eec",
                                    callerid="/b")  # fmt: skip
        for k in range(n):
            writer.write(js, T0 + k * 10**7, _joint_state(k))
            writer.write(tfa if k % 2 else tfb, T0 + k * 10**7 + 1, _tf(k, f"c{k % 2}"))
    return path


def _all(bag: Rosbag1, topics: list[str], **kw: int) -> list[tuple[int, str, Any]]:
    out = []
    for block in bag.blocks(topics, **kw):
        for t, topic, data in block.messages():
            out.append((t, topic, typestore().deserialize_cdr(bytes(data), bag.topics[topic].msgtype)))
    return out


@pytest.mark.parametrize("compression", ["none", "bz2", "lz4"])
def test_each_compression_reads_what_was_written(tmp_path: Path, compression: str) -> None:
    bag = Rosbag1(_write(tmp_path / f"{compression}.bag", compression))
    assert bag.note == ""
    assert set(bag.topics) == {"/joint_states", "/tf"}
    assert bag.topics["/joint_states"].msgtype == "sensor_msgs/msg/JointState"
    assert bag.topics["/tf"].msgtype == "tf2_msgs/msg/TFMessage"
    assert (bag.topics["/tf"].count, bag.topics["/joint_states"].count) == (300, 300)
    assert bag.topics["/tf"].encoding == "ros1msg" and "TransformStamped" in bag.topics["/tf"].definition
    assert bag.span == (T0, T0 + 299 * 10**7 + 1)
    got = _all(bag, ["/joint_states", "/tf"])
    assert [t for t, _, _ in got] == sorted(T0 + k * 10**7 + d for k in range(300) for d in (0, 1))
    states = [m for _, topic, m in got if topic == "/joint_states"]
    assert [s.header.stamp.sec for s in states] == list(range(300))
    assert states[10].name == ["a", "b"] and states[10].position.tolist() == [10.0, 11.0]
    assert states[10].header.frame_id == "base" and states[10].header.stamp.nanosec == 5
    tfs = [m.transforms[0] for _, topic, m in got if topic == "/tf"]  # both connections, one stream
    assert [(x.child_frame_id, x.transform.translation.x) for x in tfs[:3]] == [("c0", 0), ("c1", 1), ("c0", 2)]
    assert tfs[5].header.frame_id == "odom" and tfs[5].transform.rotation.w == 1.0
    bag.close()


def test_only_the_stretch_and_topics_asked_for(tmp_path: Path) -> None:
    bag = Rosbag1(_write(tmp_path / "a.bag", "lz4"))
    got = _all(bag, ["/joint_states"], start_ns=T0 + 100 * 10**7, stop_ns=T0 + 110 * 10**7)
    assert [m.header.stamp.sec for _, _, m in got] == list(range(100, 110))
    assert {topic for _, topic, _ in got} == {"/joint_states"}
    assert list(bag.blocks(["/nothing"])) == []
    t, data = bag.last("/joint_states", before_ns=T0 + 50 * 10**7) or (0, b"")
    assert t == T0 + 49 * 10**7
    assert typestore().deserialize_cdr(data, "sensor_msgs/msg/JointState").header.stamp.sec == 49
    t, _ = bag.last("/tf") or (0, b"")
    assert t == T0 + 299 * 10**7 + 1
    assert bag.last("/joint_states", before_ns=T0) is None


def test_the_blocks_skip_chunks_outside_the_stretch(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    bag = Rosbag1(_write(tmp_path / "a.bag", "bz2"))
    read: list[int] = []
    original = bag._records.chunk_data
    monkeypatch.setattr(bag._records, "chunk_data", lambda pos, **kw: read.append(pos) or original(pos, **kw))
    _all(bag, ["/joint_states"], start_ns=T0 + 290 * 10**7)
    assert 0 < len(read) <= 2 < len(bag._records.chunks)


def test_agrees_with_rosbags_reader(tmp_path: Path) -> None:
    """rosbags' own ROS 1 reader, then its ROS 1 → CDR conversion with the store ``rosbags-convert`` builds (Noetic's
    types with ROS 2's Header), as the independent source."""
    from rosbags.rosbag1 import Reader

    convert = get_typestore(Stores.EMPTY)
    convert.register(
        {**NOETIC.fielddefs, "std_msgs/msg/Header": get_typestore(Stores.ROS2_HUMBLE).fielddefs["std_msgs/msg/Header"]}
    )

    path = _write(tmp_path / "a.bag", "lz4")
    with Reader(path) as reader:
        conns = [c for c in reader.connections if c.topic == "joint_states"]  # rosbags keeps the name
        assert conns
        expected = [
            (t, bytes(convert.ros1_to_cdr(d, "sensor_msgs/msg/JointState"))) for _, t, d in reader.messages(conns)
        ]
    bag = Rosbag1(path)
    got = [(t, bytes(d)) for b in bag.blocks(["/joint_states"]) for t, _, d in b.messages()]
    assert got == expected


def test_an_empty_name_list_and_a_pre_2010_roslib_header(tmp_path: Path) -> None:
    path = tmp_path / "old.bag"
    definition, _ = NOETIC.generate_msgdef("geometry_msgs/msg/PoseStamped")
    old = definition.replace("std_msgs/Header", "roslib/Header")
    assert "MSG: roslib/Header" in old and "std_msgs" not in old
    pose = NOETIC.types["geometry_msgs/msg/PoseStamped"](
        header=_header(3, "map", seq=99),
        pose=NOETIC.types["geometry_msgs/msg/Pose"](
            position=NOETIC.types["geometry_msgs/msg/Point"](x=1.5, y=-2.0, z=0.25),
            orientation=NOETIC.types["geometry_msgs/msg/Quaternion"](x=0, y=0, z=0, w=1),
        ),
    )
    with Writer(path) as writer:
        c = writer.add_connection("pose", "geometry_msgs/msg/PoseStamped", msgdef=old, md5sum="0" * 32)
        writer.write(c, T0, NOETIC.serialize_ros1(pose, "geometry_msgs/msg/PoseStamped"))
        j = writer.add_connection("joint_states", "sensor_msgs/msg/JointState", typestore=NOETIC)
        writer.write(j, T0 + 1, _joint_state(0, names=[]))
    bag = Rosbag1(path)
    assert bag.note == ""
    (_, _, got), (_, _, state) = _all(bag, ["/pose", "/joint_states"])
    assert (got.header.frame_id, got.header.stamp.sec, got.pose.position.x, got.pose.position.z) == (
        "map",
        3,
        1.5,
        0.25,
    )
    assert state.name == [] and len(state.position) == 0


def _index_pos(data: bytes) -> int:
    at = data.index(b"index_pos=") + len(b"index_pos=")
    return int(struct.unpack_from("<Q", data, at)[0])


def test_a_bag_without_index_is_scanned_with_one_note(tmp_path: Path) -> None:
    for compression in ("none", "lz4"):
        data = bytearray(_write(tmp_path / f"{compression}.bag", compression).read_bytes())
        pos = _index_pos(data)
        at = data.index(b"index_pos=") + len(b"index_pos=")
        data[at : at + 8] = bytes(8)  # the recorder never came back to write it
        unindexed = tmp_path / f"unindexed-{compression}.bag"
        unindexed.write_bytes(bytes(data[:pos]))
        bag = Rosbag1(unindexed)
        assert "no index" in bag.note and "breaks off" not in bag.note
        assert (bag.topics["/tf"].count, bag.topics["/joint_states"].count) == (300, 300)
        got = _all(bag, ["/joint_states", "/tf"])
        assert len(got) == 600 and [m.header.stamp.sec for _, tp, m in got if tp == "/joint_states"] == list(range(300))
        assert bag.span == (T0, T0 + 299 * 10**7 + 1)


def test_a_bag_cut_anywhere_gives_what_can_be_read(tmp_path: Path) -> None:
    for compression in ("none", "bz2"):
        data = _write(tmp_path / f"{compression}.bag", compression).read_bytes()
        end = _index_pos(data)
        counts = []
        for cut in (7000, end // 3, end // 2 + 17, end - 5, end + 20):
            path = tmp_path / f"cut-{compression}-{cut}.bag"
            path.write_bytes(data[:cut])
            bag = Rosbag1(path)
            assert "breaks off" in bag.note or "no index" in bag.note
            got = _all(bag, list(bag.topics))
            stamps = [m.header.stamp.sec for _, tp, m in got if tp == "/joint_states"]
            assert stamps == list(range(len(stamps)))  # a prefix, in order
            counts.append(len(stamps))
        assert counts == sorted(counts) and counts[-1] == 300 and counts[1] > 0
        if compression == "none":
            assert 0 < counts[0] < counts[1]  # an uncompressed chunk cut short still gives its first messages


def test_not_a_bag(tmp_path: Path) -> None:
    for content in (b"", b"hello world, not a bag at all", b"#ROSBAG V2.0\n\xff\xff\xff\xff"):
        path = tmp_path / "x.bag"
        path.write_bytes(content)
        with pytest.raises(ValueError, match=r"x\.bag"):
            Rosbag1(path)
    (tmp_path / "old.bag").write_bytes(b"#ROSBAG V1.2\n" + bytes(100))
    with pytest.raises(ValueError, match=r"old\.bag: ROS 1 bag format 1\.2: only 2\.0"):
        Rosbag1(tmp_path / "old.bag")
    with pytest.raises(OSError):
        Rosbag1(tmp_path / "missing.bag")


def test_damaged_bytes_never_hang(tmp_path: Path) -> None:
    """Bytes flipped all over the file: opening and reading end (an error or what can be read), quickly."""
    data = _write(tmp_path / "a.bag", "lz4", n=60).read_bytes()
    rng = np.random.default_rng(3)
    for k in range(60):
        damaged = bytearray(data)
        for at in rng.integers(13, len(data), size=1 + k % 4):
            damaged[at] = int(rng.integers(0, 256))
        path = tmp_path / f"d{k}.bag"
        path.write_bytes(bytes(damaged))
        try:
            bag = Rosbag1(path)
            _all(bag, list(bag.topics))
            bag.last("/tf")
        except Exception:  # any error is fine (the Bag turns it into one warning); a hang is not
            continue


def test_several_types_on_one_topic_keep_the_first(tmp_path: Path) -> None:
    path = tmp_path / "mixed.bag"
    with Writer(path) as writer:
        a = writer.add_connection("/x", "sensor_msgs/msg/JointState", typestore=NOETIC)
        b = writer.add_connection("/x", "std_msgs/msg/String", typestore=NOETIC)
        writer.write(a, T0, _joint_state(1))
        writer.write(b, T0 + 1, bytes(NOETIC.serialize_ros1(NOETIC.types["std_msgs/msg/String"](data="hi"),
                                                            "std_msgs/msg/String")))  # fmt: skip
    bag = Rosbag1(path)
    assert "/x: connections with other types" in bag.note
    assert [m.header.stamp.sec for _, _, m in _all(bag, ["/x"])] == [1]


REAL = Path(__file__).parents[2] / "data" / "bags" / "ros1"


def test_a_real_bag_recorded_by_rosbag() -> None:
    """turtlesim and the tf2 demo, recorded by ROS 1's rosbag (tests/data/bags/ros1/README.md): every /tf and
    /turtle1/cmd_vel value as rosbags' own reader and ROS 1 deserializer give it."""
    from rosbags.highlevel import AnyReader

    path = REAL / "example-lz4.bag"
    expected: dict[str, list[tuple[int, Any]]] = {"/tf": [], "/turtle1/cmd_vel": []}
    with AnyReader([path]) as reader:
        conns = [c for c in reader.connections if c.topic in expected]
        for conn, t, data in reader.messages(conns):
            expected[conn.topic].append((t, reader.deserialize(data, conn.msgtype)))
    bag = Rosbag1(path)
    assert bag.note == ""
    assert bag.topics["/tf"].msgtype == "tf2_msgs/msg/TFMessage" and bag.topics["/tf"].count == 2688
    assert bag.topics["/turtle1/pose"].msgtype == "turtlesim/msg/Pose"  # not in Humble: its bag's definition
    got = _all(bag, list(expected))
    tf = [(t, m) for t, topic, m in got if topic == "/tf"]
    assert [t for t, _ in tf] == [t for t, _ in expected["/tf"]]
    for (_, ours), (_, theirs) in zip(tf, expected["/tf"], strict=True):
        a, b = ours.transforms[0], theirs.transforms[0]
        assert (a.header.frame_id, a.child_frame_id, a.header.stamp.nanosec) == (
            b.header.frame_id,
            b.child_frame_id,
            b.header.stamp.nanosec,
        )
        assert (a.transform.translation.x, a.transform.translation.y) == (b.transform.translation.x,
                                                                           b.transform.translation.y)  # fmt: skip
    twists = [m.linear.x for _, topic, m in got if topic == "/turtle1/cmd_vel"]
    assert twists == [m.linear.x for _, m in expected["/turtle1/cmd_vel"]] and len(twists) == 357


def test_a_real_bag_whose_chunks_are_out_of_time_order() -> None:
    bag = Rosbag1(REAL / "example-unsorted-chunks.bag")
    got = _all(bag, ["/foo"])
    assert [t for t, _, _ in got] == [1_000_000_000, 2_000_000_000, 3_000_000_000]
    assert bag.span == (1_000_000_000, 3_000_000_000)
    assert (bag.last("/foo", before_ns=2_500_000_000) or (0, b""))[0] == 2_000_000_000


def test_messages_are_found_through_the_index_records_and_a_bad_offset_is_counted(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = _write(tmp_path / "a.bag", "lz4")
    bag = Rosbag1(path)
    records = bag._records
    _, _, _, pos = records.read(records.chunks[0].pos, data=False)
    _, _, data_at, _ = records.read(pos)  # the first index record after the first chunk
    bag.close()
    data = bytearray(path.read_bytes())
    data[data_at + 8 : data_at + 12] = struct.pack("<I", 0xFFFFFF00)  # its first message's offset, far outside
    damaged = tmp_path / "damaged.bag"
    damaged.write_bytes(bytes(data))

    def no_parsing(buf: bytes) -> Any:
        raise AssertionError("the chunk's records were parsed: its index records were not used")

    monkeypatch.setattr("r2d2_viz.sources.bags.rosbag1.chunk_records", no_parsing)
    bag = Rosbag1(damaged)
    got = _all(bag, ["/joint_states", "/tf"])
    assert len(got) == 599
    ((count, why),) = bag.bad_messages.values()
    assert count == 1 and "outside its chunk" in why


def test_a_noetic_marker_array_decodes_through_its_own_definition(tmp_path: Path) -> None:
    """The issue's case in a ROS 1 bag: Noetic's Marker (no texture fields) → CDR in the bag's layout →
    ``to_humble`` → the usual decoder, with the values written."""
    from r2d2_viz.msgs.definitions import to_humble
    from r2d2_viz.msgs.markers import decode_marker_array
    from r2d2_viz.msgs.shapes import Boxes, DecodeOptions

    t = NOETIC.types
    marker = t["visualization_msgs/msg/Marker"](
        header=_header(3, "odom"),
        ns="n",
        id=4,
        type=1,
        action=0,
        pose=t["geometry_msgs/msg/Pose"](
            position=t["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=3.0),
            orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
        ),
        scale=t["geometry_msgs/msg/Vector3"](x=2.0, y=4.0, z=6.0),
        color=t["std_msgs/msg/ColorRGBA"](r=0.0, g=1.0, b=0.0, a=1.0),
        lifetime=t["builtin_interfaces/msg/Duration"](sec=0, nanosec=0),
        frame_locked=False,
        points=[],
        colors=[],
        text="",
        mesh_resource="",
        mesh_use_embedded_materials=False,
    )
    array = t["visualization_msgs/msg/MarkerArray"](markers=[marker])
    path = tmp_path / "markers.bag"
    with Writer(path) as writer:
        c = writer.add_connection("markers", "visualization_msgs/msg/MarkerArray", typestore=NOETIC)
        writer.write(c, T0, NOETIC.serialize_ros1(array, "visualization_msgs/msg/MarkerArray"))
    bag = Rosbag1(path)
    info = bag.topics["/markers"]
    convert = to_humble(info.msgtype, info.definition, info.encoding)
    assert convert is not None  # Noetic's layout is not Humble's
    ((_, data),) = next(iter(bag.blocks(["/markers"]))).pairs()
    (op,) = decode_marker_array(convert(data), DecodeOptions())
    assert (op.ns, op.id, op.action) == ("n", 4, "add")
    assert op.decoded is not None and (op.decoded.frame_id, op.decoded.stamp_ns) == ("odom", 3_000_000_005)
    (box,) = op.decoded.items
    assert isinstance(box, Boxes)
    np.testing.assert_allclose(box.half_sizes, [[1.0, 2.0, 3.0]])
    np.testing.assert_array_equal(box.colors[0], [0, 255, 0, 255])


def test_a_topic_whose_definition_cannot_be_used_is_named_once(tmp_path: Path) -> None:
    path = tmp_path / "bad-def.bag"
    with Writer(path) as writer:
        bad = writer.add_connection("/odd", "odd_msgs/msg/Odd", msgdef="this is } not a definition", md5sum="0" * 32)
        good = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=NOETIC)
        writer.write(bad, T0, b"\x00\x00\x00\x00")
        writer.write(good, T0 + 1, _joint_state(2))
    bag = Rosbag1(path)
    assert bag.note.count("/odd") == 1 and "cannot be used" in bag.note
    assert set(bag.topics) == {"/joint_states"}
    assert [m.header.stamp.sec for _, _, m in _all(bag, ["/joint_states", "/odd"])] == [2]


def test_runs_of_one_shape_are_converted_together_and_agree_with_rosbags(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One chunk of 300 JointStates and 300 tf messages (two child names of one length): all converted as runs,
    every byte as rosbags' reader and conversion give it."""
    from rosbags.rosbag1 import Reader

    import r2d2_viz.sources.bags.rosbag1 as module

    path = _write(tmp_path / "one-chunk.bag", "none", threshold=1 << 20)
    batched: list[int] = []
    original = module.convert_runs
    monkeypatch.setattr(module, "convert_runs", lambda *a: batched.append(len(r := original(*a))) or r)
    convert = get_typestore(Stores.EMPTY)
    convert.register(
        {**NOETIC.fielddefs, "std_msgs/msg/Header": get_typestore(Stores.ROS2_HUMBLE).fielddefs["std_msgs/msg/Header"]}
    )
    with Reader(path) as reader:
        expected = {
            (t, bytes(convert.ros1_to_cdr(d, "sensor_msgs/msg/JointState")))
            for c, t, d in reader.messages()
            if c.topic == "joint_states"
        }
    bag = Rosbag1(path)
    got = {
        (t, bytes(d))
        for b in bag.blocks(["/joint_states", "/tf"])
        for t, topic, d in b.messages()
        if topic == "/joint_states"
    }
    assert got == expected and len(got) == 300
    assert batched == [600]


def _seq_by_topic(bag: Rosbag1, topics: list[str]) -> dict[str, list[tuple[int, int]]]:
    got: dict[str, list[tuple[int, int]]] = {}
    for block in bag.blocks(topics):
        assert block.seq is not None
        for i, (t, topic, _) in enumerate(block.messages()):
            got.setdefault(topic, []).append((t, int(block.seq[i])))
    return got


def test_header_seq_beside_the_messages_as_rosbags_reads_it(tmp_path: Path) -> None:
    """ROS 1's ``header.seq`` (dropped by the conversion to CDR) comes with each message; golden: rosbags' reader
    and ``deserialize_ros1``; -1 for a type without a header. Also with the index gone (the scan)."""
    from seqbags import seqs, write

    path = write(tmp_path / "seq.bag")
    data = bytearray(path.read_bytes())
    pos = _index_pos(data)
    at = data.index(b"index_pos=") + len(b"index_pos=")
    data[at : at + 8] = bytes(8)
    unindexed = tmp_path / "unindexed.bag"
    unindexed.write_bytes(bytes(data[:pos]))
    for p in (path, unindexed):
        got = _seq_by_topic(Rosbag1(p), ["/temp", "/ref", "/value", "/pair"])
        for topic in ("/temp", "/ref", "/pair"):
            assert got[topic] == seqs(path, topic), (p, topic)
        assert {s for _, s in got["/value"]} == {-1}
        assert [s for _, s in got["/temp"]][3:7] == [103, 104, 108, 109]  # by hand: slots 5, 6, 7 never recorded
        assert (Rosbag1(p).topics["/temp"].publishers, Rosbag1(p).topics["/pair"].publishers) == (1, 2)


def test_header_seq_of_the_real_turtlesim_bag() -> None:
    """The real ROS 1 bag's ``/rosout`` (the only topic with a header): seq as rosbags deserialises it."""
    from seqbags import seqs

    path = Path(__file__).parents[2] / "data/bags/ros1/example-lz4.bag"
    got = _seq_by_topic(Rosbag1(path), ["/rosout"])["/rosout"]
    assert got == seqs(path, "/rosout") and len(got) == 10


def test_a_topic_written_after_the_others_is_merged_in_flight(tmp_path: Path) -> None:
    """Issue 38 (``--video``'s 1 GB on a bag written topic by topic): rosbags' ROS 1 writer, 30 joint states padded
    to 300 kB (a chunk each), then 30 small ones at the times between (one chunk spanning them all): every chunk
    overlaps the last. Reading both topics, each block dropped before the next, holds the chunks in flight
    (tracemalloc: a few MB), not the whole file joined at once (18 MB); messages and their ``header.seq`` are what
    rosbags' reader gives, in time order."""
    import tracemalloc

    from rosbags.rosbag1 import Reader

    path = tmp_path / "sequential.bag"
    writer = Writer(path)
    writer.chunk_threshold = 200_000
    with writer:
        big = writer.add_connection("/big", "sensor_msgs/msg/JointState", typestore=NOETIC)
        small = writer.add_connection("/small", "sensor_msgs/msg/JointState", typestore=NOETIC)
        for k in range(30):
            writer.write(big, T0 + k * 10**7, _joint_state(k, [f"j{k}_" + "x" * 300_000]))
        for k in range(30):
            writer.write(small, T0 + k * 10**7 + 1, _joint_state(100 + k))
    with Reader(path) as reader:
        assert len(list(reader.chunk_infos)) == 31  # each big one in a chunk of its own, the small ones in one
        expected = sorted(
            ((t, c.topic, NOETIC.deserialize_ros1(bytes(d), c.msgtype)) for c, t, d in reader.messages()),
            key=lambda m: m[0],
        )
    bag, got, seqs, peaks = Rosbag1(path), [], [], []
    tracemalloc.start()
    try:
        for block in bag.blocks(["/big", "/small"]):
            peaks.append(tracemalloc.get_traced_memory()[1] - sum(len(d) for _, _, d in got))  # less what is kept
            got += [(t, topic, bytes(d)) for t, topic, d in block.messages()]
            seqs += [] if block.seq is None else block.seq.tolist()
            del block
            tracemalloc.reset_peak()
    finally:
        tracemalloc.stop()
    assert [(t, topic) for t, topic, _ in got] == [(t, topic) for t, topic, _ in expected]
    decoded = [typestore().deserialize_cdr(d, "sensor_msgs/msg/JointState") for _, _, d in got]
    assert [m.name for m in decoded] == [m.name for _, _, m in expected]
    assert seqs == [m.header.seq for _, _, m in expected] == [7] * 60
    assert max(peaks) < 3_000_000, peaks  # a big chunk or two and the step being joined, not 18 MB
