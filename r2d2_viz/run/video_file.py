"""Frames into a video file with PyAV (the ``[video]`` extra, FFmpeg in its wheels): ``.mp4`` (H.264, yuv420p, what
every player and browser plays) or ``.gif`` (FFmpeg's GIF encoder, 8-bit colour), at a constant frame rate.

Frames are written in order, one per :meth:`VideoFile.add`, with ``pts`` = their index in a time base of
1 / fps; a frame of another size than the video's is scaled to it (swscale, bicubic).
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from r2d2_viz.errors import UsageError
from r2d2_viz.msgs.images import load_av

SUFFIXES = (".mp4", ".gif")
MP4_CRF = 20
"""x264's constant quality (0 lossless … 51): 20 keeps the thin grid lines and text of a view sharp."""
MAX_SIDE = 4096
"""The largest --size side (H.264 level 5.2's widest frame); 16 the smallest, as SVT-AV1's."""


def parse_size(text: str) -> tuple[int, int]:
    """``--size 1280x720`` → (1280, 720): each side even (yuv420p halves them) and within 16 … 4096."""
    width, sep, height = text.lower().partition("x")
    if not (sep and width.isdigit() and height.isdigit()):
        raise UsageError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, such as 1280x720")
    size = (int(width), int(height))
    if not all(16 <= side <= MAX_SIDE and side % 2 == 0 for side in size):
        raise UsageError(f"--size {text!r}: each side must be an even number of pixels from 16 to {MAX_SIDE}")
    return size


def video_suffix(path: Path) -> str:
    """``.mp4`` or ``.gif`` (any case); anything else a :class:`UsageError` naming the file."""
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise UsageError(f"--render {path}: unknown extension {path.suffix or '(none)'!r}; write a .mp4 or a .gif")
    return suffix


class VideoFile:
    """An open video file of ``size`` at ``fps``, an MP4 or (``gif``) a GIF whatever ``path``'s name: :meth:`add`
    each frame (HxWx3 uint8 RGB), then :meth:`close`."""

    def __init__(self, path: Path, size: tuple[int, int], fps: float, *, gif: bool) -> None:
        av = load_av()
        self.size, self.frames, self.gif = size, 0, gif
        rate = Fraction(fps).limit_denominator(1001)
        self._container: Any = av.open(str(path), "w", format="gif" if self.gif else "mp4")
        stream: Any = self._container.add_stream("gif" if self.gif else "libx264", rate=rate)
        stream.width, stream.height = size
        stream.pix_fmt = "rgb8" if self.gif else "yuv420p"
        stream.time_base = 1 / rate
        if not self.gif:
            stream.options = {"crf": str(MP4_CRF), "preset": "veryfast"}
        self._stream = stream

    def add(self, rgb: np.ndarray) -> None:
        av = load_av()
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb[..., :3]), format="rgb24")
        width, height = self.size
        frame = frame.reformat(width=width, height=height, format=self._stream.pix_fmt, interpolation="BICUBIC")
        frame.pts = self.frames
        self.frames += 1
        self._container.mux(self._stream.encode(frame))

    def close(self) -> None:
        """Drain the encoder and write the file's end (the MP4's index)."""
        try:
            self._container.mux(self._stream.encode(None))
        finally:
            self._container.close()

    def abandon(self) -> None:
        """Close without draining (the file is removed by the caller)."""
        try:
            self._container.close()
        except Exception:
            pass
