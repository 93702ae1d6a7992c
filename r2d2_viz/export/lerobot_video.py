"""A camera's frames as LeRobot's videos: an MP4 of one stream, ``yuv420p``, one frame every ``1/fps`` from 0
(pts = frame index, time base ``1/fps``), encoded with PyAV as LeRobot's ``encode_video_frames`` does with its
default ``VideoEncoderConfig`` (``libsvtav1``, GOP 2, CRF 30, preset 12, ``fast-decode=0``); ``h264`` (libx264)
on request with the same GOP and CRF. Messages of the camera become RGB frames here too: raw images (8-bit, or
16-bit scaled to 8), compressed images (JPEG, PNG) and compressed video (H.264, H.265, AV1, VP9) decoded by PyAV.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any, Literal

import numpy as np

from r2d2_viz.msgs.images import decode_compressed_image, decode_image, load_av, video_codec
from r2d2_viz.msgs.shapes import CompressedImage, DecodeOptions, Image
from r2d2_viz.msgs.typestore import MsgError, deserialize

Codec = Literal["av1", "h264"]
SETTINGS: dict[str, dict[str, Any]] = {
    "av1": {"encoder": "libsvtav1", "g": 2, "crf": 30, "preset": 12, "fast_decode": 0},
    "h264": {"encoder": "libx264", "g": 2, "crf": 30},
}
"""LeRobot 0.6.1's ``VideoEncoderConfig`` defaults (``lerobot/configs/video.py``) and what they become as codec
options (``get_codec_options``)."""
CAMERA_TYPES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage", "foxglove_msgs/msg/CompressedVideo")
_OPTIONS = DecodeOptions()


class CameraError(MsgError):
    """A camera message that cannot become a frame (an encoding, a size)."""


def rgb8(image: Image) -> np.ndarray:
    """An ``(H, W, 3)`` uint8 frame of a raw image (16-bit scaled to 8 bits; float images refused)."""
    pixels = image.pixels
    if pixels.dtype == np.uint16:
        pixels = (pixels.astype(np.uint16) >> 8).astype(np.uint8)
    elif pixels.dtype != np.uint8:
        raise CameraError(f"{image.encoding} images are not colour or grey levels; not a camera for a dataset")
    if pixels.ndim == 2:
        return np.repeat(pixels[:, :, None], 3, axis=2)
    if image.color_model in ("BGR", "BGRA"):
        return np.ascontiguousarray(pixels[:, :, 2::-1])
    return np.ascontiguousarray(pixels[:, :, :3])


class FrameReader:
    """One camera topic's messages → RGB frames, in the topic's order (a video stream is decoded message by message,
    so every message goes through :meth:`frame`, or :meth:`skip` for an image not shown)."""

    def __init__(self, msgtype: str) -> None:
        self.msgtype = msgtype
        self._decoder: Any = None
        self._last: np.ndarray | None = None

    def frame(self, data: bytes | memoryview) -> np.ndarray | None:
        """The frame of a message; for a video, the latest decoded (None before its first keyframe)."""
        if self.msgtype == "sensor_msgs/msg/Image":
            item = decode_image(data, _OPTIONS).items[0]
            assert isinstance(item, Image)
            return rgb8(item)
        av = load_av()
        if self.msgtype == "sensor_msgs/msg/CompressedImage":
            msg = deserialize(data, "sensor_msgs/msg/CompressedImage")
            if video_codec(str(msg.format)) is not None:
                return self._video(str(msg.format), bytes(msg.data))
            item = decode_compressed_image(data, _OPTIONS).items[0]
            assert isinstance(item, CompressedImage)
            name = "png" if item.media_type == "image/png" else "mjpeg"
            frames = av.CodecContext.create(name, "r").decode(av.Packet(item.data))
            if not frames:
                raise CameraError(f"a {item.media_type} image that does not decode")
            rgb: np.ndarray = frames[-1].to_ndarray(format="rgb24")
            return rgb
        msg = deserialize(data, "foxglove_msgs/msg/CompressedVideo")
        return self._video(str(msg.format), bytes(msg.data))

    def _video(self, fmt: str, sample: bytes) -> np.ndarray | None:
        av = load_av()
        if self._decoder is None:
            codec = video_codec(fmt)
            name = {"H264": "h264", "H265": "hevc", "AV1": "libdav1d", "VP9": "vp9"}[str(codec)]
            self._decoder = av.CodecContext.create(name, "r")
        try:
            for decoded in self._decoder.decode(av.Packet(sample)):
                self._last = decoded.to_ndarray(format="rgb24")
        except av.error.FFmpegError as exc:  # a stream that starts mid-GOP: frames before its first keyframe
            if self._last is not None:
                raise CameraError(f"a video sample that does not decode ({exc})") from None
        return self._last


class Mp4Writer:
    """Frames ``(H, W, 3)`` uint8 → ``path``, one every ``1/fps``, as LeRobot encodes an episode's camera."""

    def __init__(self, path: Path, *, fps: int, codec: Codec) -> None:
        self.path, self.fps, self.codec = path, fps, codec
        self.frames = 0
        self._out: Any = None
        self._stream: Any = None
        self.size: tuple[int, int] | None = None

    def write(self, frame: np.ndarray) -> None:
        av = load_av()
        height, width = frame.shape[:2]
        if self._out is None:
            if width % 2 or height % 2:
                raise CameraError(f"{width}x{height} images: yuv420p video needs an even width and height")
            settings = SETTINGS[self.codec]
            options = {"g": str(settings["g"]), "crf": str(settings["crf"])}
            if self.codec == "av1":
                options |= {"preset": str(settings["preset"]), "svtav1-params": "fast-decode=0"}
            self._out = av.open(str(self.path), "w", format="mp4")
            self._stream = self._out.add_stream(settings["encoder"], self.fps, options=options)
            self._stream.width, self._stream.height, self._stream.pix_fmt = width, height, "yuv420p"
            self._stream.time_base = Fraction(1, self.fps)
            self.size = (height, width)
        elif self.size is not None and self.size != (height, width):
            raise CameraError(f"the image size changed from {self.size[1]}x{self.size[0]} to {width}x{height}")
        video = av.VideoFrame.from_ndarray(frame, format="rgb24")
        video.pts = self.frames
        self.frames += 1
        for packet in self._stream.encode(video):
            self._out.mux(packet)

    def close(self) -> None:
        if self._out is None:
            return
        try:
            for packet in self._stream.encode(None):
                self._out.mux(packet)
        finally:
            self._out.close()
            self._out = None
