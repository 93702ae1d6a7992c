"""A bag read once as windows (sources/playback.BagPass): every message of the wanted topics once, in time order
across topics, windows bounded by samples and bytes, stretches (segments) read as asked; and read_ahead, which
reads the windows in a thread. Bags written by rosbags; what they hold read back by rosbags' own reader."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from bagmaker import T0, TS, BagSpec, joint_state, storage_file, string, tf_message, write_bag
from displaybags import odometry
from rosbags.rosbag2 import Reader

from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.base import ArraySource
from r2d2_viz.sources.playback import BagPass, Segment, Window, read_ahead, source_windows

MS = 1_000_000
ODOM = "nav_msgs/msg/Odometry"
JOINTS = ["a", "b"]


def _bag(tmp_path: Path, storage: str = "mcap", n: int = 3000) -> Path:
    """Joint states every ms, /tf every 4th, odometry every 10th (a display topic), a description (not read)."""
    spec = BagSpec(
        types={
            "/odom": ODOM,
            "/joint_states": "sensor_msgs/msg/JointState",
            "/tf": "tf2_msgs/msg/TFMessage",
            "/robot_description": "std_msgs/msg/String",
        }
    )
    spec.add("/robot_description", T0, string("<robot/>"))
    for k in range(n):
        t = T0 + k * MS
        spec.add("/joint_states", t + 1, joint_state(t, JOINTS, [k, -k]))
        if k % 4 == 0:
            spec.add("/tf", t + 2, tf_message([(t, "odom", "base", (k, 0, 0), (0, 0, 0, 1))]))
        if k % 10 == 0:
            spec.add("/odom", t + 3, odometry(k, float(k)))
    return write_bag(tmp_path / storage, spec, storage=storage)


def _reference(path: Path) -> dict[str, list[tuple[int, bytes]]]:
    """What rosbags reads: topic → (receive time, bytes), in time order."""
    out: dict[str, list[tuple[int, bytes]]] = {}
    with Reader(path) as reader:
        for c, t, data in reader.messages():
            out.setdefault(c.topic, []).append((t, bytes(data)))
    return {topic: sorted(messages) for topic, messages in out.items()}


def _pass(bag, segments=None) -> BagPass:  # type: ignore[no-untyped-def]
    segments = segments or [Segment(("/joint_states", "/tf", "/odom"))]
    return BagPass(bag, segments, actuated=JOINTS, displays={"/odom": ODOM})


def _times(windows: list[Window]) -> dict[str, list[int]]:
    """The receive times each topic's messages came out at, window after window."""
    return {
        "/joint_states": [int(t) for w in windows if w.joints is not None for t in w.joints.times_ns],
        "/tf": [int(t) for w in windows if w.tf is not None for t in w.tf.times_ns],
        "/odom": [m.time_ns for w in windows for m in w.displays],
    }


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_every_message_once_in_time_order_across_topics(tmp_path: Path, storage: str) -> None:
    path = _bag(tmp_path, storage)
    expected = _reference(storage_file(path))
    with open_bag(path) as bag:
        windows = list(_pass(bag).windows(500))
    got = _times(windows)
    for topic in ("/joint_states", "/tf", "/odom"):
        assert got[topic] == [t for t, _ in expected[topic]], topic
    # the display messages are the bag's bytes, and the joint positions what rosbags decodes
    assert [bytes(m.data) for w in windows for m in w.displays] == [d for _, d in expected["/odom"]]
    positions = np.vstack([w.joints.positions for w in windows if w.joints is not None])
    decoded = [TS.deserialize_cdr(d, "sensor_msgs/msg/JointState").position for _, d in expected["/joint_states"]]
    np.testing.assert_array_equal(positions, np.vstack(decoded))
    # time order across topics: a window holds what came after the previous window's end, up to its own end
    previous = -1
    for w in windows:
        inside = [
            *(w.joints.times_ns.tolist() if w.joints is not None else []),
            *(w.tf.times_ns.tolist() if w.tf is not None else []),
            *(m.time_ns for m in w.displays),
        ]
        assert inside and previous < min(inside) and max(inside) == w.end_ns
        previous = w.end_ns


def test_windows_are_bounded_by_samples_and_by_bytes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = _bag(tmp_path)
    expected = _reference(storage_file(path))
    wanted = [m for topic in ("/joint_states", "/tf", "/odom") for m in expected[topic]]
    total = sum(len(d) for _, d in wanted)
    with open_bag(path) as bag:
        windows = list(_pass(bag).windows(64))
        assert all(w.joints is None or len(w.joints) <= 64 for w in windows)
        assert sum(w.nbytes for w in windows) == total  # progress counts every byte once
        assert _times(windows)["/joint_states"] == [t for t, _ in expected["/joint_states"]]
        limit = 4096
        small = list(_pass(bag).windows(100_000, max_bytes=limit))
    biggest = max(len(d) for _, d in wanted)
    assert len(small) > total // limit and all(w.nbytes <= limit + biggest for w in small)
    assert sum(w.nbytes for w in small) == total
    assert _times(small) == _times(windows)


def test_segments_read_their_stretch_and_topics(tmp_path: Path) -> None:
    """A seek's shape: the transforms and joint states of a stretch before the offset, then everything after."""
    path = _bag(tmp_path)
    expected = _reference(storage_file(path))
    a, b = T0 + 1000 * MS, T0 + 1500 * MS
    segments = [Segment(("/joint_states", "/tf"), a, b), Segment(("/joint_states", "/tf", "/odom"), b, None)]
    with open_bag(path) as bag:
        got = _times(list(_pass(bag, segments).windows(200)))
    for topic in ("/joint_states", "/tf"):
        assert got[topic] == [t for t, _ in expected[topic] if t >= a]
    assert got["/odom"] == [t for t, _ in expected["/odom"] if t >= b]


def test_a_generated_motion_as_windows() -> None:
    times = np.arange(10, dtype=np.int64) * MS
    windows = list(source_windows(ArraySource(times, ["j"], np.arange(10.0)[:, None]), 4))
    assert [len(w.joints) for w in windows if w.joints is not None] == [4, 4, 2]
    assert [w.end_ns for w in windows] == [3 * MS, 7 * MS, 9 * MS]


def _counted(n: int | None, fail_at: int | None = None) -> tuple[Iterator[Window], list[int]]:
    made: list[int] = []

    def windows() -> Iterator[Window]:
        k = 0
        while n is None or k < n:
            if k == fail_at:
                raise ValueError("damaged at 3")
            made.append(k)
            yield Window(k)
            k += 1

    return windows(), made


def test_read_ahead_hands_on_every_window_in_order() -> None:
    windows, _ = _counted(50)
    assert [w.end_ns for w in read_ahead(windows)] == list(range(50))


def test_read_ahead_passes_the_readers_exception_on() -> None:
    windows, _ = _counted(10, fail_at=3)
    got: list[int] = []
    with pytest.raises(ValueError, match="damaged at 3"):
        for w in read_ahead(windows):
            got.append(w.end_ns)
    assert got == [0, 1, 2]


def test_read_ahead_stops_its_reader_when_the_consumer_stops() -> None:
    windows, made = _counted(None)  # endless: only a stop ends it
    ahead = read_ahead(windows, depth=2)
    assert next(ahead).end_ns == 0
    ahead.close()  # the consumer stops (Ctrl-C, an error while writing)
    deadline = time.monotonic() + 10
    while any(t.name == "r2d2-viz bag reader" for t in threading.enumerate()) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(t.name == "r2d2-viz bag reader" for t in threading.enumerate())
    assert len(made) <= 5  # it read no further than its depth ahead


def _zstd_bag(tmp_path: Path, n: int = 40) -> Path:
    """A bag of zstd-compressed chunks (rosbags' storage compression; it closes a chunk past 1 MiB): a 300 kB
    String every 10 ms, hardly compressible, and a small /tf between each two."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.rosbag2.enums import CompressionFormat, CompressionMode

    rng = np.random.default_rng(0)
    path = tmp_path / "zstd"
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with writer:
        big = writer.add_connection("/blob", "std_msgs/msg/String", typestore=TS)
        tf = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=TS)
        for k in range(n):
            t = T0 + k * 10 * MS
            text = "".join(map(chr, rng.integers(33, 127, 300_000)))
            writer.write(big, t, string(text))
            writer.write(tf, t + MS, tf_message([(t, "odom", "base", (k, 0, 0), (0, 0, 0, 1))]))
    return path


def test_windows_of_a_small_topic_are_sized_by_what_is_read(tmp_path: Path) -> None:
    """A small topic of a bag of compressed chunks: each chunk is decompressed whole for it, so a window holds about
    ``max_bytes`` of decompressed chunks (not ``max_bytes`` of the topic, which would be every chunk of the bag),
    and a block keeps a copy of the topic's messages, not the decompressed chunk."""
    path = _zstd_bag(tmp_path)
    expected = _reference(storage_file(path))["/tf"]
    with open_bag(path) as bag:
        blocks = list(bag.blocks(["/tf"]))
        limit = 2 << 20
        windows = list(BagPass(bag, [Segment(("/tf",))], actuated=None, displays={}).windows(100_000, limit))
    chunk = 1 << 20  # rosbags closes a chunk once it holds more than 1 MiB: four strings and three /tf
    assert [bytes(b.data(i)) for b in blocks for i in range(len(b))] == [d for _, d in expected]
    assert all(len(b.buffer) < 4096 for b in blocks)
    # decompressed up to the last /tf of each chunk (three strings of its four); the last chunk is what was left
    # at the end: /tf alone (kept as it is)
    assert all(len(b.buffer) == b.nbytes and 900_000 < b.read_nbytes < chunk for b in blocks[:-1])
    # 40 × 300 kB: ~9 MB decompressed for 40 small messages, in windows of about 2 MB read each
    assert len(windows) >= 9_000_000 // (limit + 2 * chunk)
    assert [int(t) for w in windows if w.tf is not None for t in w.tf.times_ns] == [t for t, _ in expected]
