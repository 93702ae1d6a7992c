"""A bag's display topics as one stream of raw messages in receive-time order (sources/bag_displays, read by the
bag's one pass, sources/playback.BagPass), on bags rosbags wrote."""

from __future__ import annotations

from pathlib import Path

import pytest
from displaybags import MAP_TIME, SCAN_TIMES, T0, write_display_bag
from rosbags.rosbag2 import Reader

from r2d2_viz.sources.bag_displays import display_topics, frames_of
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.plan import plan_bag
from r2d2_viz.sources.playback import BagPass, Segment


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_the_display_topics_merged_by_receive_time_as_rosbags_reads_them(tmp_path: Path, storage: str) -> None:
    path = write_display_bag(tmp_path / "bag", storage=storage)
    with Reader(path) as reader:  # rosbags' own reader: what the bag holds, in receive-time order
        expected = [
            (t, c.topic, bytes(data))
            for c, t, data in sorted(reader.messages(), key=lambda m: m[1])
            if c.topic in ("/scan", "/markers", "/map", "/odom")
        ]
    with open_bag(path) as bag:
        shown, other = display_topics(bag)
        assert shown == {
            "/map": "nav_msgs/msg/OccupancyGrid",
            "/markers": "visualization_msgs/msg/MarkerArray",
            "/odom": "nav_msgs/msg/Odometry",
            "/scan": "sensor_msgs/msg/LaserScan",
        }
        assert other == {"/chatter": "std_msgs/msg/ColorRGBA"}  # /tf and /tf_static are the robot pipeline's
        windows = BagPass(bag, [Segment(tuple(shown))], actuated=None, displays=shown).windows(1000)
        messages = [m for w in windows for m in w.displays]
        assert all(m.msgtype == shown[m.topic] for m in messages)
        got = [(m.time_ns, m.topic, bytes(m.data)) for m in messages]
        assert [t for t, _, _ in got] == sorted(t for t, _, _ in got)  # in receive-time order
        assert sorted(got) == sorted(expected)  # (messages received at the same time: any order)
        assert got[0][0] == T0 and (MAP_TIME, "/map") in [(t, topic) for t, topic, _ in got]
        assert sum(topic == "/scan" for _, topic, _ in got) == len(SCAN_TIMES) + 2  # + empty frame, garbage
        # the frames they are drawn in: a leading '/' is stripped as tf2 does, an empty id and garbage left out
        assert frames_of(messages) == {"base_laser", "odom"}
        # the plan's preview (what the view is fitted to): the first 16 messages as the pass reads them, then the
        # first two of every topic in its 2 s look-ahead (their frames are checked against the TF tree)
        previewed = plan_bag(bag).preview_messages
        preview = [(m.time_ns, m.topic, bytes(m.data)) for m in previewed]
        assert preview[:16] == got[:16] and set(preview) <= set(got)
        firsts = {topic: [g for g in got if g[1] == topic and g[0] < T0 + 2 * 10**9][:2] for topic in shown}
        assert all(set(first) <= set(preview) for first in firsts.values())
        assert frames_of(previewed) == {"base_laser", "odom"}


def test_a_seek_finds_each_videos_keyframe_before_it_and_leaves_images_alone(tmp_path: Path) -> None:
    """Keyframes every 60 samples at 5 Hz (12 s apart, PyAV's encoder says which): a seek to 11 s searches back
    2, 4, 8 then 16 s and sends from the keyframe at 0 s; a JPEG CompressedImage topic is never read back."""
    av = pytest.importorskip("av")
    from fractions import Fraction

    import numpy as np
    from camerabag import write_video_bag

    from r2d2_viz.sources.bag_displays import video_preroll

    encoder = av.CodecContext.create("libx264", "w")
    encoder.width, encoder.height, encoder.pix_fmt = 64, 48, "yuv420p"
    encoder.time_base, encoder.gop_size, encoder.max_b_frames = Fraction(1, 5), 60, 0
    encoder.options = {"tune": "zerolatency", "preset": "ultrafast", "sc_threshold": "0"}
    packets: list[tuple[bytes, bool]] = []
    rng = np.random.default_rng(1)
    for i in range(70):
        frame = av.VideoFrame.from_ndarray(rng.integers(0, 255, (48, 64, 3), dtype=np.uint8), format="rgb24")
        frame.pts = i
        packets += [(bytes(p), bool(p.is_keyframe)) for p in encoder.encode(frame)]
    packets += [(bytes(p), bool(p.is_keyframe)) for p in encoder.encode(None)]
    assert [i for i, (_, key) in enumerate(packets) if key] == [0, 60]
    step = 200_000_000
    jpeg = b"\xff\xd8\xff\xe0" + bytes(60)
    samples = [("/video", T0 + i * step, "h264", p) for i, (p, _) in enumerate(packets)]
    samples += [("/cam/compressed", T0 + i * step + 1, "jpeg", jpeg) for i in range(70)]
    write_video_bag(tmp_path / "bag", sorted(samples, key=lambda s: s[1]))
    with open_bag(tmp_path / "bag") as bag:
        shown, _ = display_topics(bag)
        read: list[tuple[str, ...]] = []
        blocks = bag.blocks
        bag.blocks = lambda topics, **kw: (read.append(tuple(topics)), blocks(topics, **kw))[1]  # type: ignore[method-assign]
        found = video_preroll(bag, shown, T0 + 11 * 10**9)
    assert [m.time_ns for m in found] == [T0 + i * step for i in range(55)]  # 0 to 10.8 s: before the seek
    assert all(m.topic == "/video" for m in found)
    assert all(packets[i][0] in bytes(m.data) for i, m in enumerate(found))  # each sample in its message's CDR
    assert ("/cam/compressed",) not in read and read.count(("/video",)) == 5  # 2, 4, 8, 16 s back; then the samples
