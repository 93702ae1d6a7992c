"""Frames into .mp4 and .gif with PyAV, read back with PyAV's decoder; --size and the suffix checked."""

from __future__ import annotations

from pathlib import Path

import av
import numpy as np
import pytest

from r2d2_viz.errors import UsageError
from r2d2_viz.run.video_file import VideoFile, parse_size, video_suffix

RED, BLUE = (220, 30, 30), (30, 30, 220)


def _frames(path: Path) -> tuple[list[np.ndarray], av.video.stream.VideoStream]:
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        return [f.to_ndarray(format="rgb24") for f in container.decode(stream)], stream


def _solid(rgb: tuple[int, int, int], size: tuple[int, int]) -> np.ndarray:
    return np.broadcast_to(np.array(rgb, np.uint8), (size[1], size[0], 3)).copy()


def test_sizes() -> None:
    assert parse_size("1280x720") == (1280, 720)
    assert parse_size("64X48") == (64, 48)
    for bad in ("1280", "x720", "12.5x10", "-64x48", "641x480", "8x8", "8192x64", "axb"):
        with pytest.raises(UsageError, match="--size"):
            parse_size(bad)


def test_suffixes() -> None:
    assert video_suffix(Path("a.MP4")) == ".mp4"
    assert video_suffix(Path("a.gif")) == ".gif"
    for bad in ("a.avi", "a", "a.rrd"):
        with pytest.raises(UsageError, match=r"--render .*: unknown extension"):
            video_suffix(Path(bad))


@pytest.mark.parametrize(("name", "gif", "codec"), [("v.mp4", False, "h264"), ("v.gif", True, "gif")])
def test_every_frame_is_written_in_order_at_the_rate(tmp_path: Path, name: str, gif: bool, codec: str) -> None:
    path = tmp_path / name
    video = VideoFile(path, (64, 48), 4.0, gif=gif)
    for k in range(10):
        video.add(_solid(RED if k < 5 else BLUE, (64, 48)))
    video.close()
    frames, stream = _frames(path)
    assert stream.codec_context.name == codec and (stream.width, stream.height) == (64, 48)
    assert len(frames) == 10
    if not gif:
        assert stream.average_rate == 4
    # a flat colour survives yuv420p (H.264) or GIF's 8-bit palette within a few levels
    tol = 40 if gif else 6
    for k, frame in enumerate(frames):
        want = np.array(RED if k < 5 else BLUE)
        assert np.abs(frame.reshape(-1, 3).mean(0) - want).max() < tol, k


def test_a_frame_of_another_size_is_scaled_to_the_video(tmp_path: Path) -> None:
    path = tmp_path / "v.mp4"
    video = VideoFile(path, (64, 48), 30.0, gif=False)
    left = _solid(RED, (33, 25))
    left[:, 17:] = BLUE  # left half red, right half blue, at an odd size
    video.add(left)
    video.close()
    [frame], _ = _frames(path)
    assert frame.shape == (48, 64, 3)
    assert frame[24, 8, 0] > 150 and frame[24, 56, 2] > 150
