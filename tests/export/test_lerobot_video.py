"""A camera's frames as LeRobot's MP4: read back with PyAV; quality as luma PSNR (numpy)."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from camerabag import Frames

from r2d2_viz.export.lerobot_video import CameraError, Mp4Writer, rgb8
from r2d2_viz.msgs.shapes import Image


def psnr_luma(a: np.ndarray, b: np.ndarray) -> float:
    w = np.array([0.299, 0.587, 0.114])
    mse = float(np.mean((a.astype(np.float64) @ w - b.astype(np.float64) @ w) ** 2))
    return 10 * np.log10(255.0**2 / max(mse, 1e-12))


@pytest.mark.parametrize("codec", ["av1", "h264"])
def test_frames_at_i_over_fps_decode_close_to_the_input(tmp_path: Path, codec: str) -> None:
    import av

    frames = Frames(160, 120)
    writer = Mp4Writer(tmp_path / "cam.mp4", fps=15, codec=codec)  # type: ignore[arg-type]
    for i in range(12):
        writer.write(frames(i))
    writer.close()
    with av.open(str(tmp_path / "cam.mp4")) as container:
        stream = container.streams.video[0]
        assert stream.codec_context.name in (("libdav1d", "av1") if codec == "av1" else ("h264",))
        got = [(f.time, f.to_ndarray(format="rgb24")) for f in container.decode(stream)]
        assert stream.pix_fmt == "yuv420p" and stream.average_rate == Fraction(15)
    assert [round(t * 15, 6) for t, _ in got] == list(range(12))  # LeRobot reads frame k at k / fps
    assert min(psnr_luma(img, frames(i)) for i, (_, img) in enumerate(got)) >= 35.0


def test_odd_sizes_and_size_changes_are_one_clear_error(tmp_path: Path) -> None:
    with pytest.raises(CameraError, match="15x10 images"):
        Mp4Writer(tmp_path / "a.mp4", fps=30, codec="av1").write(np.zeros((10, 15, 3), np.uint8))
    writer = Mp4Writer(tmp_path / "b.mp4", fps=30, codec="h264")
    writer.write(np.zeros((16, 16, 3), np.uint8))
    with pytest.raises(CameraError, match="changed from 16x16 to 32x16"):
        writer.write(np.zeros((16, 32, 3), np.uint8))
    writer.close()


def test_raw_images_become_rgb8() -> None:
    bgr = np.array([[[1, 2, 3]]], dtype=np.uint8)
    assert rgb8(Image(bgr, "BGR", "bgr8")).tolist() == [[[3, 2, 1]]]
    mono16 = np.array([[0x1234]], dtype=np.uint16)
    assert rgb8(Image(mono16, "L", "mono16")).tolist() == [[[0x12, 0x12, 0x12]]]
    with pytest.raises(CameraError, match="32FC1"):
        rgb8(Image(np.zeros((1, 1), np.float32), "L", "32FC1"))


@pytest.mark.parametrize("fmt", ["jpeg", "png"])
def test_compressed_images_decode_as_pillow_reads_them(fmt: str) -> None:
    """A CompressedImage written by rosbags with Pillow's JPEG or PNG: the frame is Pillow's own decoding (PNG:
    exactly; JPEG: two decoders' rounding apart, ≥ 40 dB)."""
    import io

    from bagmaker import TS, Header, stamp
    from PIL import Image as PilImage

    from r2d2_viz.export.lerobot_video import FrameReader

    pixels = Frames(64, 48)(3)
    blob = io.BytesIO()
    PilImage.fromarray(pixels).save(blob, format=fmt.upper(), quality=95)
    msg = TS.types["sensor_msgs/msg/CompressedImage"](
        Header(stamp(5), "cam"), fmt, np.frombuffer(blob.getvalue(), np.uint8)
    )
    data = bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/CompressedImage"))
    frame = FrameReader("sensor_msgs/msg/CompressedImage").frame(data)
    assert frame is not None
    pillow = np.asarray(PilImage.open(io.BytesIO(blob.getvalue())).convert("RGB"))
    if fmt == "png":
        assert np.array_equal(frame, pillow)
    else:
        assert psnr_luma(frame, pillow) >= 40.0
