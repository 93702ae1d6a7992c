"""Video samples: keyframes and well-formed bitstreams told apart as PyAV's encoders mark them (the golden values:
``Packet.is_keyframe`` of FFmpeg's libx264, libx265, libsvtav1 and libvpx-vp9), and the encoder's refusals."""

from __future__ import annotations

from fractions import Fraction

import av
import numpy as np
import pytest
from camerabag import Frames

from r2d2_viz.msgs.images import VideoEncoder, is_keyframe, video_codec
from r2d2_viz.msgs.shapes import Image
from r2d2_viz.msgs.typestore import MsgError

ENCODERS = {"H264": "libx264", "H265": "libx265", "AV1": "libsvtav1", "VP9": "libvpx-vp9"}
OPTIONS = {
    "H264": {"tune": "zerolatency", "preset": "ultrafast"},
    "H265": {"tune": "zerolatency", "preset": "ultrafast", "x265-params": "log-level=none"},
    "AV1": {"preset": "12", "svtav1-params": "pred-struct=1"},
    "VP9": {"deadline": "realtime", "cpu-used": "8", "lag-in-frames": "0"},
}


def packets(codec: str, n: int = 12, gop: int = 5) -> list[tuple[bytes, bool]]:
    encoder = av.CodecContext.create(ENCODERS[codec], "w")
    encoder.width, encoder.height, encoder.pix_fmt = 160, 120, "yuv420p"
    encoder.time_base, encoder.framerate, encoder.gop_size, encoder.max_b_frames = Fraction(1, 30), 30, gop, 0
    encoder.options = OPTIONS[codec]
    frames, out = Frames(160, 120), []
    for i in range(n):
        frame = av.VideoFrame.from_ndarray(frames(i), format="rgb24")
        frame.pts = i
        out += [(bytes(p), bool(p.is_keyframe)) for p in encoder.encode(frame)]
    out += [(bytes(p), bool(p.is_keyframe)) for p in encoder.encode(None)]
    return out


@pytest.mark.parametrize("codec", ["H264", "H265", "AV1", "VP9"])
def test_keyframes_as_the_encoder_marks_them(codec: str) -> None:
    stream = packets(codec)  # type: ignore[arg-type]
    assert sum(key for _, key in stream) >= 2
    assert [is_keyframe(codec, data) for data, _ in stream] == [key for _, key in stream]  # type: ignore[arg-type]


@pytest.mark.parametrize("codec", ["H264", "H265", "AV1", "VP9"])
def test_bytes_that_are_no_bitstream_are_refused(codec: str) -> None:
    for junk in (b"", b"\x00", b"\x47\x11\x22\x33" * 8, b"\xff" * 40):
        with pytest.raises(MsgError):
            is_keyframe(codec, junk)  # type: ignore[arg-type]


def test_formats_naming_a_video_codec() -> None:
    assert [video_codec(f) for f in ("h264", "H.264", "HEVC", "av1", "vp9", "rgb8; h264", "jpeg", "png", "")] == [
        "H264", None, "H265", "AV1", "VP9", "H264", None, None, None,
    ]  # fmt: skip


def test_the_encoder_takes_8_bit_even_images_and_refuses_others_once() -> None:
    encoder = VideoEncoder("av1")
    assert encoder.takes(Image(np.zeros((48, 64, 3), np.uint8), "RGB", "rgb8"))
    assert not encoder.takes(Image(np.zeros((48, 64), np.uint16), "L", "16UC1"))  # depth: lossless, said nothing
    assert encoder.notes == []
    odd = VideoEncoder("av1")
    assert not odd.takes(Image(np.zeros((47, 64, 3), np.uint8), "RGB", "rgb8"))
    assert not odd.takes(Image(np.zeros((48, 64, 3), np.uint8), "RGB", "rgb8"))  # the topic stays lossless
    assert len(odd.notes) == 1 and "64x47" in odd.notes[0]


def test_a_keyframe_every_two_seconds_of_message_time_and_one_sample_per_frame() -> None:
    encoder, frames = VideoEncoder("av1"), Frames(160, 120)
    keys = []
    for i in range(25):  # 10 Hz: keyframes at 0, 2 s
        samples = encoder.encode(Image(frames(i), "RGB", "rgb8"), i * 100_000_000)
        assert len(samples) == 1
        keys.append(samples[0].keyframe)
    assert [i for i, k in enumerate(keys) if k] == [0, 20]
    assert encoder.close() == 0
