"""Cameras as video (issue 32), through the real CLI: a camera bag written by rosbags saved with ``--video``, its
samples decoded back with PyAV and compared with the bag's frames (luma PSNR); Foxglove CompressedVideo passed
through byte for byte; bad input said once."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import av
import numpy as np
import pytest
from bagmaker import T0, BagSpec, write_bag
from camerabag import Frames, image, write_camera_bag, write_video_bag
from conftest import cli
from rrd import read_recording

CAMERA = "/camera/image_raw"
AV1, H264 = 0x61763031, 0x61766331  # rerun.components.VideoCodec: the fourccs 'av01' and 'avc1'


def luma(rgb: np.ndarray) -> np.ndarray:
    """Luma as FFmpeg's swscale computes it (BT.601, limited range), the decoder's reference."""
    frame = av.VideoFrame.from_ndarray(rgb, format="rgb24").reformat(format="yuv420p")
    return frame.to_ndarray(format="gray").astype(np.float64)


def decoded_luma(samples: list[bytes], codec: str) -> list[np.ndarray]:
    decoder = av.CodecContext.create("libdav1d" if codec == "av1" else "h264", "r")
    out = []
    for sample in [*samples, None]:
        frames = decoder.decode(av.Packet(sample) if sample is not None else None)
        out += [f.to_ndarray(format="gray").astype(np.float64) for f in frames]
    return out


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    return float(10 * np.log10(255**2 / np.mean((a - b) ** 2)))


def _samples(path: Path, entity: str = CAMERA) -> tuple[list[int], list[bytes], list[bool]]:
    rows = read_recording(path)[entity]
    columns = rows.times, rows.temporal["VideoStream:sample"], rows.temporal["VideoStream:is_keyframe"]
    picked = [(t, s, k) for t, s, k in zip(*columns, strict=True) if s is not None]
    return [t for t, _, _ in picked], [bytes(s[0]) for _, s, _ in picked], [bool(k[0]) for _, _, k in picked]


@pytest.mark.parametrize("codec", ["av1", "h264"])
def test_video_samples_decode_back_to_the_bags_frames(tmp_path: Path, codec: str) -> None:
    n = 75  # 2.5 s at 30 Hz: a second keyframe at 2 s
    frames = Frames()
    times = write_camera_bag(tmp_path / "cam", n, frames=frames)
    out = tmp_path / "v.rrd"
    result = cli("--bag", str(tmp_path / "cam"), "--save", str(out), "--video", codec)
    assert result.returncode == 0, result.stderr
    assert "Svt" not in result.stderr and len(result.stderr.splitlines()) <= 3, result.stderr
    rows = read_recording(out)[CAMERA]
    assert rows.static["VideoStream:codec"] == [[AV1 if codec == "av1" else H264]]
    assert "Image:buffer" not in rows.temporal  # no raw copy
    assert rows.temporal["Pinhole:image_from_camera"][0] is not None or any(rows.temporal["Pinhole:image_from_camera"])
    sample_times, samples, keys = _samples(out)
    assert sample_times == times  # one sample per frame, at its time, in order
    assert keys[0] and keys[60] and sum(keys) == 2  # a keyframe at the start and 2 s later, no more
    raw = n * 640 * 480 * 3
    assert sum(map(len, samples)) <= 0.02 * raw
    lumas = decoded_luma(samples, codec)
    assert len(lumas) == n
    scores = [psnr(d, luma(frames(i))) for i, d in enumerate(lumas)]
    assert np.mean(scores) >= 38 and min(scores) >= 34, (np.mean(scores), min(scores))


def test_a_seek_starts_the_stream_with_a_keyframe(tmp_path: Path) -> None:
    write_camera_bag(tmp_path / "cam", 60)
    out = tmp_path / "v.rrd"
    result = cli("--bag", str(tmp_path / "cam"), "--save", str(out), "--video", "--start-offset", "1.1")
    assert result.returncode == 0, result.stderr
    times, samples, keys = _samples(out)
    assert times[0] >= T0 + 1.1e9 and keys[0]
    assert len(decoded_luma(samples, "av1")) == len(samples)  # it decodes from its first sample


def _h264_packets(n: int, gop: int) -> list[bytes]:
    """An H.264 stream written by PyAV's x264 (Annex B, keyframes every ``gop`` frames, no B-frames)."""
    encoder = av.CodecContext.create("libx264", "w")
    encoder.width, encoder.height, encoder.pix_fmt = 320, 240, "yuv420p"
    encoder.time_base, encoder.gop_size, encoder.max_b_frames = Fraction(1, 30), gop, 0
    encoder.options = {"tune": "zerolatency", "preset": "ultrafast"}
    frames = Frames(320, 240)
    packets = []
    for i in range(n):
        frame = av.VideoFrame.from_ndarray(frames(i), format="rgb24")
        frame.pts = i
        packets += [bytes(p) for p in encoder.encode(frame)]
    packets += [bytes(p) for p in encoder.encode(None)]
    return packets


def test_compressed_video_is_passed_through_byte_for_byte(tmp_path: Path) -> None:
    packets = _h264_packets(40, gop=20)
    garbage = b"\x47\x11\x22\x33" * 20  # not Annex B
    samples = [("/foxglove/video", T0 + i * 33_000_000, "h264", p) for i, p in enumerate(packets) if i >= 5]
    samples.insert(20, ("/foxglove/video", T0 + 24 * 33_000_000 + 1, "h264", garbage))
    samples += [("/cam/image/compressed", T0 + i * 33_000_000 + 2, "h264", p) for i, p in enumerate(packets)]
    write_video_bag(tmp_path / "video", samples)
    out = tmp_path / "v.rrd"
    result = cli("--bag", str(tmp_path / "video"), "--save", str(out))  # no --video: nothing is encoded
    assert result.returncode == 0, result.stderr
    _, passed, keys = _samples(out, "/foxglove/video")
    assert passed == packets[20:]  # from the first keyframe on, as they are; the broken sample left out
    assert keys == [i % 20 == 0 for i in range(20, 40)]
    _, also, _ = _samples(out, "/cam/image/compressed")
    assert also == packets
    assert read_recording(out)["/foxglove/video"].static["VideoStream:codec"] == [[H264]]
    lines = result.stderr.splitlines()
    assert sum("/foxglove/video" in line and "keyframe" in line and "15 samples skipped" in line for line in lines) == 1
    assert sum("/foxglove/video" in line and "Annex B" in line for line in lines) == 1, result.stderr


def test_depth_stays_lossless_and_a_new_size_restarts_the_stream(tmp_path: Path) -> None:
    types = {"/depth/image_raw": "sensor_msgs/msg/Image", CAMERA: "sensor_msgs/msg/Image"}
    spec = BagSpec(types=types)
    small, big = Frames(320, 240), Frames(640, 480)
    for i in range(10):
        t = T0 + i * 100_000_000
        depth = np.full((240, 320), 1000 + i, np.uint16)
        spec.add("/depth/image_raw", t, image(t, depth, "16UC1"))
        spec.add(CAMERA, t + 1, image(t, (small if i < 5 else big)(i)))
    write_bag(tmp_path / "bag", spec)
    out = tmp_path / "v.rrd"
    result = cli("--bag", str(tmp_path / "bag"), "--save", str(out), "--video")
    assert result.returncode == 0, result.stderr
    recording = read_recording(out)
    depth = recording["/depth/image_raw"].temporal
    assert "VideoStream:sample" not in depth and sum(b is not None for b in depth["Image:buffer"]) == 10
    _, samples, keys = _samples(out)
    assert len(samples) == 10 and keys[0] and keys[5]
    assert sum("320x240 to 640x480" in line for line in result.stderr.splitlines()) == 1, result.stderr


def test_without_pyav_video_says_how_to_install_it(tmp_path: Path) -> None:
    write_camera_bag(tmp_path / "cam", 2)
    sitecustom = tmp_path / "site"
    sitecustom.mkdir()
    (sitecustom / "sitecustomize.py").write_text("import sys\nsys.modules['av'] = None  # as if not installed\n")
    out = tmp_path / "v.rrd"
    result = cli("--bag", str(tmp_path / "cam"), "--save", str(out), "--video", env={"PYTHONPATH": str(sitecustom)})
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == ["error: --video needs PyAV: pip install 'r2d2-viz[video]'"]
    assert not out.exists()


def test_live_video_has_a_keyframe_a_second_under_two_megabits(tmp_path: Path) -> None:
    """The live path (``--ros --video``): frames logged as they arrive (no reader thread), rate-capped."""
    import rerun as rr

    from r2d2_viz.sources.bag_displays import TopicMessage
    from r2d2_viz.viewer.display_feed import DisplayFeed, VideoFeed
    from r2d2_viz.viewer.notices import Notices

    out, frames = tmp_path / "live.rrd", Frames()
    rec = rr.RecordingStream("video_live_test")
    rec.save(out)
    feed = DisplayFeed(Notices(rec), clock="timestamp", fixed_frame="map", video=VideoFeed("av1", live=True))
    times = [T0 + round(i * 1e9 / 30) for i in range(75)]
    for i, t in enumerate(times):
        feed.log(TopicMessage(t, CAMERA, "sensor_msgs/msg/Image", image(t, frames(i))))
    feed.finish()
    rec.flush()
    rec.disconnect()
    sample_times, samples, keys = _samples(out)
    assert sample_times == times
    assert [i for i, k in enumerate(keys) if k] == [0, 30, 60]
    assert sum(map(len, samples)) * 8 / 2.5 <= 2_000_000  # bit/s over the 2.5 s
    assert len(decoded_luma(samples, "av1")) == 75


def test_a_seek_into_passed_through_video_without_a_keyframe_before_it_starts_at_its_next_one(
    tmp_path: Path,
) -> None:
    packets = _h264_packets(40, gop=20)
    samples = [("/foxglove/video", T0 + i * 33_000_000, "h264", p) for i, p in enumerate(packets) if i >= 5]
    write_video_bag(tmp_path / "video", samples)  # the recording started mid-GOP: no keyframe before frame 20
    out = tmp_path / "v.rrd"
    result = cli("--bag", str(tmp_path / "video"), "--save", str(out), "--start-offset", "0.2")  # frame 11 on
    assert result.returncode == 0, result.stderr
    times, passed, keys = _samples(out, "/foxglove/video")
    assert passed == packets[20:] and keys[0] and times[0] == T0 + 20 * 33_000_000
    assert sum("keyframe" in line for line in result.stderr.splitlines()) == 1, result.stderr


def test_a_seek_into_passed_through_video_starts_at_the_keyframe_before_it(tmp_path: Path) -> None:
    """As found: ``--start-offset 12`` into a CompressedVideo (and a CompressedImage h264) with a keyframe every
    10 s showed no video until 20 s, although the keyframe at 10 s makes the frames at 12-20 s decodable. The
    samples are sent from that keyframe on, at their own times; which samples are keyframes, PyAV's encoder says."""
    encoder = av.CodecContext.create("libx264", "w")
    encoder.width, encoder.height, encoder.pix_fmt = 160, 120, "yuv420p"
    encoder.time_base, encoder.gop_size, encoder.max_b_frames = Fraction(1, 5), 50, 0  # 5 Hz: 10 s a keyframe
    encoder.options = {"tune": "zerolatency", "preset": "ultrafast", "sc_threshold": "0"}
    frames = Frames(160, 120)
    packets: list[tuple[bytes, bool]] = []
    for i in range(150):  # 30 s
        frame = av.VideoFrame.from_ndarray(frames(i), format="rgb24")
        frame.pts = i
        packets += [(bytes(p), bool(p.is_keyframe)) for p in encoder.encode(frame)]
    packets += [(bytes(p), bool(p.is_keyframe)) for p in encoder.encode(None)]
    assert [i for i, (_, key) in enumerate(packets) if key] == [0, 50, 100]  # PyAV: keyframes at 0, 10 and 20 s
    step = 200_000_000
    samples = [("/foxglove/video", T0 + i * step, "h264", p) for i, (p, _) in enumerate(packets)]
    samples += [("/cam/image/compressed", T0 + i * step + 1, "h264", p) for i, (p, _) in enumerate(packets)]
    write_video_bag(tmp_path / "video", sorted(samples, key=lambda s: s[1]))
    out = tmp_path / "v.rrd"
    result = cli("--bag", str(tmp_path / "video"), "--save", str(out), "--start-offset", "12")
    assert result.returncode == 0, result.stderr
    for topic, offset in (("/foxglove/video", 0), ("/cam/image/compressed", 1)):
        times, sent, keys = _samples(out, topic)
        assert times == [T0 + i * step + offset for i in range(50, 150)], topic  # from the keyframe at 10 s
        assert sent == [p for p, _ in packets[50:]] and keys == [key for _, key in packets[50:]]
        assert len(decoded_luma(sent, "h264")) == 100  # every sample decodes from the first one sent
    assert "keyframe" not in result.stderr, result.stderr
