"""Opening bags: every form and metadata version, real ROS 2 bags, and bad bags (one line, or what could be read
and one warning)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from bagmaker import T0, TS, BagSpec, joint_state, storage_file, string, tf_message, write_bag
from conftest import REPO
from rosbags.rosbag2 import CompressionFormat, CompressionMode, Reader, StoragePlugin, Writer
from rosbags.rosbag2.storage_mcap import McapReader

from r2d2_viz.errors import BagError
from r2d2_viz.sources.bags.bag import open_bag

REAL = REPO / "tests" / "data" / "bags"
HELLO = [f"Hello, world! {i}" for i in range(10)]  # what the ROS 2 demo talker published


def _strings(bag, topic: str) -> list[str]:
    return [bag.deserialize(data, "std_msgs/msg/String").data for _, data in bag.raw(topic)]


def _spec(n: int = 20) -> BagSpec:
    spec = BagSpec().add("/robot_description", T0, string("<robot name='r'/>"))
    for k in range(n):
        spec.add("/joint_states", T0 + k * 10**7, joint_state(T0 + k * 10**7, ["a"], [k]))
    return spec


@pytest.mark.parametrize("real", ["talker_db3", "talker_db3/talker.db3", "talker_mcap", "talker_mcap/talker.mcap"])
def test_real_ros2_bags_directory_and_single_file(real: str) -> None:
    """Recorded by ROS 2 (rosbag2's own test bags): metadata version 4, QoS written as ROS did."""
    with open_bag(REAL / real) as bag:
        assert bag.topics["/topic"].msgtype == "std_msgs/msg/String"
        assert bag.topics["/topic"].count == 10
        assert _strings(bag, "/topic") == HELLO
        times = [t for t, _ in bag.raw("/topic")]
        assert times == sorted(times) and times[0] == 1585866235112609068  # the file's own first timestamp


def _listing(folder: Path) -> dict[str, tuple[int, int]]:
    return {p.name: (p.stat().st_size, p.stat().st_mtime_ns) for p in folder.iterdir()}


@pytest.mark.parametrize("version", [1, 2, 3, 4, 5, 6, 7, 8, 9])
@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_every_metadata_version_and_storage(tmp_path: Path, storage: str, version: int) -> None:
    path = write_bag(tmp_path / "b", _spec(), storage=storage, version=version)
    before = _listing(path)
    for form in (path, storage_file(path)):
        with open_bag(form) as bag:
            assert bag.files == (storage_file(path),)
            assert bag.topics["/joint_states"].count == 20
            assert [t for t, _ in bag.raw("/joint_states")] == [T0 + k * 10**7 for k in range(20)]
            assert _strings(bag, "/robot_description") == ["<robot name='r'/>"]
    assert _listing(path) == before  # nothing written beside the bag, nothing touched


@pytest.mark.parametrize("real", ["talker_db3", "talker_mcap"])
def test_reading_a_real_bag_changes_nothing_in_its_folder(real: str) -> None:
    before = _listing(REAL / real)
    with open_bag(REAL / real) as bag:
        assert len(list(bag.raw("/topic"))) == 10
    assert _listing(REAL / real) == before


def test_split_bag_reads_every_file_in_order(tmp_path: Path) -> None:
    a = write_bag(tmp_path / "a", _spec(5))
    b = BagSpec().add("/joint_states", T0 + 10**9, joint_state(T0 + 10**9, ["a"], [99]))
    b = write_bag(tmp_path / "b", b)
    bag_dir = tmp_path / "split"
    bag_dir.mkdir()
    (bag_dir / "split_0.mcap").write_bytes(storage_file(a).read_bytes())
    (bag_dir / "split_1.mcap").write_bytes(storage_file(b).read_bytes())
    meta = (a / "metadata.yaml").read_text().replace("- a.mcap", "- split_0.mcap\n  - split_1.mcap")
    (bag_dir / "metadata.yaml").write_text(meta)
    with open_bag(bag_dir) as bag:
        times = [t for t, _ in bag.raw("/joint_states")]
    assert times == [T0 + k * 10**7 for k in range(5)] + [T0 + 10**9]


def _error(path: Path) -> str:
    with pytest.raises(BagError) as info:
        open_bag(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message
    return message


def test_missing_and_wrong_paths(tmp_path: Path) -> None:
    assert "no such file" in _error(tmp_path / "nothing.mcap")
    (tmp_path / "notes.txt").write_text("hi")
    assert "not a bag (expected a rosbag2 directory, a .mcap or .db3 file, or a ROS 1 .bag file)" in _error(
        tmp_path / "notes.txt"
    )
    (tmp_path / "dir").mkdir()
    (tmp_path / "dir" / "notes.txt").write_text("hi")
    assert "not a ROS 2 bag (no metadata.yaml, no .db3 or .mcap file" in _error(tmp_path / "dir")


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_directory_without_metadata_reads_like_a_bag(tmp_path: Path, storage: str) -> None:
    """What ``ros2 bag reindex`` repairs: the storage files are there, metadata.yaml is not."""
    path = write_bag(tmp_path / "b", _spec(), storage=storage)
    (path / "metadata.yaml").unlink()
    before = _listing(path)
    warnings: list[str] = []
    with open_bag(path, warn=warnings.append) as bag:
        assert bag.files == (storage_file(path),)
        assert bag.topics["/joint_states"].count == 20
        assert [t for t, _ in bag.raw("/joint_states")] == [T0 + k * 10**7 for k in range(20)]
        assert _strings(bag, "/robot_description") == ["<robot name='r'/>"]
    assert warnings == [] and _listing(path) == before


@pytest.mark.parametrize("suffix", [".mcap", ".db3"])
def test_split_bag_without_metadata_reads_its_files_in_number_order(tmp_path: Path, suffix: str) -> None:
    """Eleven split files: ``bag_10`` comes after ``bag_9``, not after ``bag_1``."""
    storage = "mcap" if suffix == ".mcap" else "sqlite3"
    bag_dir = tmp_path / "split"
    bag_dir.mkdir()
    for k in range(11):
        t = T0 + k * 10**9
        one = write_bag(
            tmp_path / f"part{k}", BagSpec().add("/joint_states", t, joint_state(t, ["a"], [k])), storage=storage
        )
        shutil.copy(storage_file(one), bag_dir / f"bag_{k}{suffix}")
    with open_bag(bag_dir) as bag:
        assert [f.name for f in bag.files] == [f"bag_{k}{suffix}" for k in range(11)]
        assert bag.topics["/joint_states"].count == 11
        assert [t for t, _ in bag.raw("/joint_states")] == [T0 + k * 10**9 for k in range(11)]


def test_directory_without_metadata_and_two_storages(tmp_path: Path) -> None:
    bag_dir = tmp_path / "mixed"
    bag_dir.mkdir()
    for storage in ("mcap", "sqlite3"):
        shutil.copy(storage_file(write_bag(tmp_path / storage, _spec(), storage=storage)), bag_dir)
    assert "both .db3 and .mcap" in _error(bag_dir)


def test_directory_without_metadata_and_a_junk_file(tmp_path: Path) -> None:
    bag_dir = tmp_path / "junk"
    bag_dir.mkdir()
    (bag_dir / "junk_0.db3").write_bytes(os.urandom(4096))
    assert "cannot read this bag" in _error(bag_dir)


@pytest.mark.parametrize("suffix", [".mcap", ".db3"])
def test_junk_and_empty_files(tmp_path: Path, suffix: str) -> None:
    junk = tmp_path / f"junk{suffix}"
    junk.write_bytes(os.urandom(4096))
    assert "cannot read this bag" in _error(junk)
    empty = tmp_path / f"empty{suffix}"
    empty.write_bytes(b"")
    assert "cannot read this bag" in _error(empty)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_bag_without_messages(tmp_path: Path, storage: str) -> None:
    path = tmp_path / "none"
    with Writer(
        path, version=9, storage_plugin=StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    ) as w:
        w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=TS)
    assert "empty bag" in _error(path)
    assert "empty bag" in _error(storage_file(path))


def test_bad_metadata(tmp_path: Path) -> None:
    path = write_bag(tmp_path / "b", _spec())
    meta = path / "metadata.yaml"
    text = meta.read_text()
    meta.write_text("rosbag2_bagfile_information: [1, 2")
    assert "not rosbag2 metadata" in _error(path)
    meta.write_text(text.replace("relative_file_paths", "relative_paths"))
    assert "not rosbag2 metadata" in _error(path)
    meta.write_text(text.replace("b.mcap", "gone.mcap"))
    assert "missing: gone.mcap" in _error(path)


def test_compressed_bag_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "z"
    w = Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3)
    w.set_compression(CompressionMode.FILE, CompressionFormat.ZSTD)
    w.open()
    c = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=TS)
    w.write(c, T0, joint_state(T0, ["a"], [1.0]))
    w.close()
    assert "compressed bags" in _error(path)


def test_truncated_db3_is_one_line(tmp_path: Path) -> None:
    path = write_bag(tmp_path / "b", _spec(3000), storage="sqlite3")
    file = storage_file(path)
    cut = tmp_path / "cut.db3"
    cut.write_bytes(file.read_bytes()[: file.stat().st_size // 2])
    assert "cannot read this bag" in _error(cut)


def test_truncated_mcap_gives_what_was_recorded_and_one_warning(tmp_path: Path) -> None:
    """A recorder killed mid-way leaves an MCAP file with no footer: its complete chunks are read."""
    path = write_bag(tmp_path / "b", _spec(20000))
    full = storage_file(path).read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(full[: int(len(full) * 0.6)])
    warnings: list[str] = []
    with open_bag(cut, warn=warnings.append) as bag:
        times = [t for t, _ in bag.raw("/joint_states")]
    assert 1000 < len(times) < 20000
    assert times == [T0 + k * 10**7 for k in range(len(times))]  # the first ones, in order, none lost between
    assert len(warnings) == 1 and f"recovered {len(times) + 1} messages" in warnings[0]  # + /robot_description

    # the same file inside its rosbag2 directory: the metadata knows how many there were
    shutil.copy(cut, storage_file(path))
    warnings.clear()
    with open_bag(path, warn=warnings.append) as bag:
        assert len(list(bag.raw("/joint_states"))) == len(times)
    assert warnings == [  # said once, when the bag is opened, with what the metadata lists
        f"{storage_file(path)}: the file breaks off (no footer, no index): recovered {len(times) + 1} messages "
        "(the metadata lists 20001)"
    ]


def test_corrupt_mcap_chunk(tmp_path: Path) -> None:
    """Bytes overwritten in the middle: the messages of every other chunk (their places from rosbags' reading of
    the chunk index), and one warning, said once however often the bag is read."""
    path = write_bag(tmp_path / "b", _spec(20000))
    data = bytearray(storage_file(path).read_bytes())
    middle = len(data) // 2
    data[middle : middle + 4096] = b"\xff" * 4096
    reader = McapReader(storage_file(path))
    reader.open()
    (hit,) = [c for c in reader.chunks if c.chunk_start_offset <= middle < c.chunk_start_offset + c.chunk_length]
    reader.close()
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    warnings: list[str] = []
    with open_bag(bad, warn=warnings.append) as bag:
        times = [t for t, _ in bag.raw("/joint_states")]
        assert len(list(bag.raw("/joint_states"))) == len(times)
    expected = [T0 + k * 10**7 for k in range(20000)]
    assert times == [t for t in expected if not hit.message_start_time <= t <= hit.message_end_time]
    assert 0 < len(times) < 20000
    assert len(warnings) == 1 and "1 chunk skipped" in warnings[0] and f"recovered {len(times)} of 20000" in warnings[0]


def test_wrong_type_on_a_topic(tmp_path: Path) -> None:
    spec = BagSpec(types={"/joint_states": "std_msgs/msg/String"}).add("/joint_states", T0, string("hi"))
    path = write_bag(tmp_path / "b", spec)
    with open_bag(path) as bag, pytest.raises(BagError, match="is std_msgs/msg/String, expected sensor_msgs"):
        bag.require_type("/joint_states", "sensor_msgs/msg/JointState")


def _three_topics(path: Path, storage: str) -> Path:
    """Joint states every 10 ms, /tf every 2nd, a description every 50th, over 3 s."""
    spec = BagSpec()
    for k in range(300):
        t = T0 + k * 10**7
        spec.add("/joint_states", t, joint_state(t, ["a"], [k]))
        if k % 2 == 0:
            spec.add("/tf", t + 1, tf_message([(t, "odom", "base", (k, 0, 0), (0, 0, 0, 1))]))
        if k % 50 == 0:
            spec.add("/robot_description", t + 2, string(f"<robot name='r{k}'/>"))
    return write_bag(path, spec, storage=storage)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_several_topics_in_one_pass_a_stretch_and_the_last_before(tmp_path: Path, storage: str) -> None:
    """Bag.blocks and Bag.last against rosbags' own reader, both storages."""
    path = _three_topics(tmp_path / "b", storage)
    with Reader(path) as reader:
        everything = sorted(((t, c.topic, bytes(d)) for c, t, d in reader.messages()), key=lambda m: m[0])
    warnings: list[str] = []
    with open_bag(path, warn=warnings.append) as bag:
        assert bag.span == (everything[0][0], everything[-1][0])
        for topics, start, stop in [
            (["/joint_states", "/tf"], None, None),
            (["/tf", "/robot_description", "/joint_states"], T0 + 5 * 10**8, T0 + 15 * 10**8 + 1),
            (["/robot_description", "/nothing"], T0 + 10**8, None),
        ]:
            got = [
                (t, topic, bytes(d))
                for b in bag.blocks(topics, start_ns=start, stop_ns=stop)
                for t, topic, d in b.messages()
            ]
            lo, hi = start or 0, stop or 2**64
            assert got == [m for m in everything if m[1] in topics and lo <= m[0] < hi], (topics, start, stop)
        descriptions = [m for m in everything if m[1] == "/robot_description"]
        assert bag.last("/robot_description") == (descriptions[-1][0], descriptions[-1][2])
        before = T0 + 2 * 10**9 + 2  # the one of 2 s (received at 2 s + 2 ns) is not before it: 1.5 s
        assert bag.last("/robot_description", before_ns=before) == (descriptions[-3][0], descriptions[-3][2])
        assert bag.last("/robot_description", before_ns=T0) is None and bag.last("/nothing") is None
    assert warnings == []


def test_the_last_message_of_a_split_bag_is_in_its_last_file_that_has_one(tmp_path: Path) -> None:
    bag_dir = tmp_path / "split"
    bag_dir.mkdir()
    parts = [
        BagSpec().add("/robot_description", T0, string("<robot name='early'/>")),
        BagSpec().add("/robot_description", T0 + 10**9, string("<robot name='late'/>")),
        BagSpec().add("/joint_states", T0 + 2 * 10**9, joint_state(T0, ["a"], [1.0])),
    ]
    for k, spec in enumerate(parts):
        shutil.copy(storage_file(write_bag(tmp_path / f"p{k}", spec)), bag_dir / f"bag_{k}.mcap")
    with open_bag(bag_dir) as bag:
        assert bag.span == (T0, T0 + 2 * 10**9)
        found = bag.last("/robot_description")
        assert found is not None and bag.deserialize(found[1], "std_msgs/msg/String").data == "<robot name='late'/>"
        early = bag.last("/robot_description", before_ns=T0 + 10**9)
        assert early is not None and early[0] == T0


def test_ros2_names_without_a_leading_slash_are_the_full_names(tmp_path: Path) -> None:
    """Issue 33, finding 8: a bag written with ``joint_states``, ``tf`` and ``robot_description`` (no leading
    slash) is the robot's bag as with ``/joint_states``…: as ROS 1 names are, they are given their slash."""
    from conftest import cli
    from rrd import read_recording, tf_by_child

    from r2d2_viz.robot.model import default_urdf_path

    types = {"joint_states": "sensor_msgs/msg/JointState", "tf": "tf2_msgs/msg/TFMessage"}
    spec = BagSpec(types={**types, "robot_description": "std_msgs/msg/String"})
    spec.add("robot_description", T0, string(default_urdf_path().read_text()))
    for k in range(5):
        t = T0 + k * 100_000_000
        spec.add("joint_states", t, joint_state(t, ["swivel", "tilt", "periscope"], [0.1 * k, 0.0, 0.0]))
        spec.add("tf", t, tf_message([(t, "odom", "axis", (0.1 * k, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))]))
    for storage in ("mcap", "sqlite3"):
        bag = write_bag(tmp_path / storage, spec, storage=storage)
        listed = cli("--bag", str(bag), "--list")
        assert listed.returncode == 0, listed.stderr
        assert [line.split()[0] for line in listed.stdout.splitlines()] == [
            "/joint_states",
            "/robot_description",
            "/tf",
        ]
        out = tmp_path / f"{storage}.rrd"
        result = cli("--bag", str(bag), "--save", str(out))
        assert result.returncode == 0, result.stderr
        assert "no display" not in result.stderr and "no robot" not in result.stderr, result.stderr
        recording = read_recording(out)
        assert len(recording["/joints/continuous"].times) == 5
        assert tf_by_child(recording)["axis"].times == [T0 + k * 100_000_000 for k in range(5)]
