"""sensor_msgs Image (a numpy view honouring ``step``), CompressedImage and CameraInfo; and cameras as video.

Cameras as video: raw 8-bit images encoded as they come (PyAV's SVT-AV1 or x264, imported only with ``--video``),
and video that is compressed already (``foxglove_msgs/CompressedVideo``, a ``CompressedImage`` whose format is a
video codec) passed through as it is, each sample checked for a well-formed bitstream and whether it is a keyframe.

Samples are one frame each, in presentation order: no B-frames, no reordering (SVT-AV1's low-delay prediction
structure, x264's zerolatency), as Rerun's ``VideoStream`` plays them in decode order. A keyframe comes at least
every ``keyint_s`` seconds of message time (2 s in a recording, 1 s live), so seeking in the viewer is immediate.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Literal

import numpy as np

from r2d2_viz.errors import R2d2VizError
from r2d2_viz.msgs.geometry import header_of
from r2d2_viz.msgs.shapes import CompressedImage, Decoded, DecodeOptions, Image, Pinhole, VideoSample
from r2d2_viz.msgs.typestore import MsgError, deserialize

ColorModel = Literal["L", "RGB", "RGBA", "BGR", "BGRA"]
# ROS encoding -> (numpy type, channels, colour model); 8UC3 / 8UC4 in OpenCV's BGR order, as cv_bridge reads them
ENCODINGS: dict[str, tuple[str, int, ColorModel]] = {
    "rgb8": ("u1", 3, "RGB"),
    "rgba8": ("u1", 4, "RGBA"),
    "bgr8": ("u1", 3, "BGR"),
    "bgra8": ("u1", 4, "BGRA"),
    "rgb16": ("u2", 3, "RGB"),
    "rgba16": ("u2", 4, "RGBA"),
    "bgr16": ("u2", 3, "BGR"),
    "bgra16": ("u2", 4, "BGRA"),
    "mono8": ("u1", 1, "L"),
    "mono16": ("u2", 1, "L"),
    "8UC1": ("u1", 1, "L"),
    "8UC3": ("u1", 3, "BGR"),
    "8UC4": ("u1", 4, "BGRA"),
    "8SC1": ("i1", 1, "L"),
    "16UC1": ("u2", 1, "L"),
    "16SC1": ("i2", 1, "L"),
    "32SC1": ("i4", 1, "L"),
    "32FC1": ("f4", 1, "L"),
    "64FC1": ("f8", 1, "L"),
}
BAYER = {f"bayer_{cfa}{bits}": cfa for cfa in ("rggb", "bggr", "gbrg", "grbg") for bits in (8, 16)}
"""Bayer mosaics (the colour filter's 2x2 cell, row by row) → RGB, each 2x2 cell one colour: its red, the mean of
its two greens, its blue (the superpixel demosaic; RViz would show the raw mosaic as grey)."""
YUV422 = {"yuv422": (1, 0, 2), "uyvy": (1, 0, 2), "yuv422_yuy2": (0, 1, 3), "yuyv": (0, 1, 3)}
"""YUV 4:2:2, two pixels in 4 bytes → RGB: where the first Y, the U and the V sit (UYVY: U Y0 V Y1; YUY2: Y0 U Y1 V;
ROS's ``yuv422`` is UYVY). BT.601 limited range, as OpenCV (cv_bridge), FFmpeg and Rerun's YUY2 read it."""


def decode_image(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """The pixels ``(H, W)`` or ``(H, W, C)`` of an Image, row padding (``step``) removed, native byte order."""
    msg = deserialize(data, "sensor_msgs/msg/Image")
    frame, stamp = header_of(msg)
    encoding = str(msg.encoding)
    spec = ENCODINGS.get(encoding) or _converted(encoding)
    if spec is None:
        raise MsgError(f"unsupported image encoding {encoding[:40]!r}")
    code, channels, model = spec
    dtype = np.dtype((">" if msg.is_bigendian else "<") + code)
    width, height, step = int(msg.width), int(msg.height), int(msg.step)
    row = width * channels * dtype.itemsize
    raw: np.ndarray = msg.data
    if step < row:
        raise MsgError(f"step {step} < {width} pixels x {channels * dtype.itemsize} bytes")
    if height * step > len(raw):
        raise MsgError(f"{height} rows of {step} bytes need {height * step} bytes, data has {len(raw)}")
    rows = raw[: height * step].reshape(height, step)[:, :row]
    pixels = np.ascontiguousarray(rows).view(dtype).reshape(height, width, channels)
    if dtype.byteorder == ">":
        pixels = pixels.astype(dtype.newbyteorder("="))
    if encoding in BAYER:
        pixels, model = debayer(pixels[:, :, 0], BAYER[encoding]), "RGB"
    elif encoding in YUV422:
        pixels, model = yuv422_rgb(pixels.reshape(height, width * 2), YUV422[encoding]), "RGB"
    image = Image(pixels[:, :, 0] if pixels.ndim == 3 and pixels.shape[2] == 1 else pixels, model, encoding)
    return Decoded(frame, stamp, (image,))


def _converted(encoding: str) -> tuple[str, int, ColorModel] | None:
    """The storage of an encoding shown converted to RGB: a Bayer mosaic (one channel), YUV 4:2:2 (two bytes a
    pixel)."""
    if encoding in BAYER:
        return ("u2" if encoding.endswith("16") else "u1"), 1, "L"
    return ("u1", 2, "L") if encoding in YUV422 else None


def debayer(mosaic: np.ndarray, cfa: str) -> np.ndarray:
    """``(H, W, 3)`` RGB of a Bayer ``mosaic`` ``(H, W)`` whose 2x2 cell is ``cfa`` (``rggb``...): each cell one
    colour; an odd last row or column takes the colour of the cell beside it."""
    height, width = mosaic.shape
    if height < 2 or width < 2:
        raise MsgError(f"a {width}x{height} Bayer image has no full 2x2 cell")
    cells = mosaic[: height // 2 * 2, : width // 2 * 2].reshape(height // 2, 2, width // 2, 2)
    at = [divmod(k, 2) for k in range(4)]
    greens = [cells[:, y, :, x].astype(np.uint32) for (y, x), c in zip(at, cfa, strict=True) if c == "g"]
    (ry, rx), (by, bx) = at[cfa.index("r")], at[cfa.index("b")]
    green = ((greens[0] + greens[1] + 1) // 2).astype(mosaic.dtype)
    rgb = np.stack([cells[:, ry, :, rx], green, cells[:, by, :, bx]], axis=-1)
    rgb = np.repeat(np.repeat(rgb, 2, axis=0), 2, axis=1)
    out: np.ndarray = np.pad(rgb, ((0, height - rgb.shape[0]), (0, width - rgb.shape[1]), (0, 0)), mode="edge")
    return out


def yuv422_rgb(packed: np.ndarray, order: tuple[int, int, int]) -> np.ndarray:
    """``(H, W, 3)`` uint8 RGB of packed YUV 4:2:2 rows ``(H, 2W)`` (``order``: offsets of Y0, U, V in each 4 bytes),
    BT.601 limited range (Y 16-235, U and V 16-240)."""
    height, row = packed.shape
    if row % 4:
        raise MsgError(f"YUV 4:2:2 needs an even width, got {row // 2}")
    quads = packed.reshape(height, row // 4, 4).astype(np.float32)
    y0, u, v = order
    luma = 1.164383 * (quads[:, :, [y0, y0 + 2]] - 16.0)  # (H, W/2, 2): both pixels of each pair
    cb, cr = (quads[:, :, u] - 128.0)[:, :, None], (quads[:, :, v] - 128.0)[:, :, None]
    rgb = np.stack([luma + 1.596027 * cr, luma - 0.391762 * cb - 0.812968 * cr, luma + 2.017232 * cb], axis=-1)
    out: np.ndarray = np.clip(np.rint(rgb), 0, 255).astype(np.uint8).reshape(height, row // 2, 3)
    return out


def media_type(blob: bytes, fmt: str) -> str:
    """``image/jpeg`` or ``image/png`` from the file's magic bytes (the ``format`` string as a fallback)."""
    if blob.startswith(b"\xff\xd8\xff"):
        return "image/jpeg"
    if blob.startswith(b"\x89PNG\r\n\x1a\n"):
        return "image/png"
    raise MsgError(f"compressed image is neither JPEG nor PNG (format {fmt[:40]!r})")


def decode_compressed_image(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A CompressedImage's JPEG or PNG bytes, or its video sample when its format names a video codec;
    ``compressedDepth`` and other formats are refused."""
    msg = deserialize(data, "sensor_msgs/msg/CompressedImage")
    frame, stamp = header_of(msg)
    blob = bytes(msg.data)
    if video_codec(str(msg.format)) is not None:
        return Decoded(frame, stamp, (video_sample(str(msg.format), blob),))
    return Decoded(frame, stamp, (CompressedImage(blob, media_type(blob, str(msg.format))),))


def decode_camera_info(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """The pinhole model of a CameraInfo (``K`` and size); an uncalibrated camera (K all zeros) draws nothing."""
    msg = deserialize(data, "sensor_msgs/msg/CameraInfo")
    frame, stamp = header_of(msg)
    K = np.asarray(msg.k, dtype=np.float64).reshape(3, 3)
    if not np.all(np.isfinite(K)):
        raise MsgError("non-finite camera matrix K")
    if K[0, 0] <= 0 or K[1, 1] <= 0 or int(msg.width) <= 0 or int(msg.height) <= 0:
        return Decoded(frame, stamp, ())
    return Decoded(frame, stamp, (Pinhole(K, int(msg.width), int(msg.height)),))


# --- cameras as video ---------------------------------------------------------------------------------

Codec = Literal["AV1", "H264", "H265", "VP9"]
EncoderName = Literal["av1", "h264"]
INSTALL = "pip install 'r2d2-viz[video]'"
VIDEO_FORMATS: dict[str, Codec] = {
    "h264": "H264", "avc": "H264", "h265": "H265", "hevc": "H265", "av1": "AV1", "vp9": "VP9",
}  # fmt: skip
"""A message's ``format`` (lower case) → the Rerun codec of its samples."""
PIXEL_FORMATS = {"RGB": "rgb24", "BGR": "bgr24", "RGBA": "rgba", "BGRA": "bgra", "L": "gray"}
VIDEO_ENCODINGS = frozenset(
    {"rgb8", "bgr8", "rgba8", "bgra8", "mono8", "8UC1", "8UC3", "8UC4", *YUV422, *(b for b in BAYER if b.endswith("8"))}
)
"""The 8-bit colour and mono encodings encoded as video; 16-bit, float and depth images stay lossless."""
CRF = {"av1": 26, "h264": 20}
"""Constant quality for recordings (luma PSNR ≥ 38 dB on a noisy textured camera: benchmarks/video.py)."""
LIVE_BITRATE = 1_800_000
"""Live: a bitrate cap (bit/s), under 2 Mbit/s for a 30 Hz 640x480 camera."""


class VideoError(R2d2VizError):
    """``--video`` without PyAV installed."""


def require_av() -> None:
    """VideoError (one line: how to install it) when PyAV is missing (checked before anything is read)."""
    load_av()


def load_av() -> Any:
    """PyAV, imported on first use (a run without ``--video`` never imports it); SVT-AV1 told to print errors
    only (its banner goes to stderr otherwise)."""
    os.environ.setdefault("SVT_LOG", "1")
    try:
        import av
    except ImportError:
        raise VideoError(f"--video needs PyAV: {INSTALL}") from None
    av.logging.set_level(av.logging.PANIC)
    return av


def video_codec(fmt: str) -> Codec | None:
    """The video codec a ``format`` string names (``h264``, ``hevc``, ``av1``, ``vp9``, any case, ``;``-separated
    parts as in ``rgb8; h264``), or None (an image format: JPEG, PNG)."""
    for part in fmt.lower().replace(";", " ").split():
        if part in VIDEO_FORMATS:
            return VIDEO_FORMATS[part]
    return None


def _annexb_units(data: bytes) -> list[int]:
    """The first byte of each NAL unit of an Annex B stream; MsgError when it does not start with a start code."""
    if not (data.startswith(b"\x00\x00\x01") or data.startswith(b"\x00\x00\x00\x01")):
        raise MsgError("not an Annex B bitstream (no start code)")
    heads = []
    at = data.find(b"\x00\x00\x01")
    while at >= 0 and at + 3 < len(data):
        heads.append(data[at + 3])
        at = data.find(b"\x00\x00\x01", at + 3)
    if not heads or any(h & 0x80 for h in heads):
        raise MsgError("not an Annex B bitstream (bad NAL header)")
    return heads


def _leb128(data: bytes, at: int) -> tuple[int, int]:
    value = 0
    for i in range(8):
        if at + i >= len(data):
            break
        byte = data[at + i]
        value |= (byte & 0x7F) << (7 * i)
        if not byte & 0x80:
            return value, at + i + 1
    raise MsgError("not an AV1 bitstream (bad OBU size)")


def _av1_keyframe(data: bytes) -> bool:
    """Walk the OBUs (low-overhead format): a keyframe has a sequence header and a KEY_FRAME frame header."""
    at, sequence, key = 0, False, False
    if not data:
        raise MsgError("empty AV1 sample")
    while at < len(data):
        head = data[at]
        obu_type, extension, has_size = (head >> 3) & 0xF, (head >> 2) & 1, (head >> 1) & 1
        if head & 0x80 or obu_type in (0, 9, 10, 11, 12, 13, 14) or not has_size:
            raise MsgError("not an AV1 bitstream (bad OBU header)")
        size, start = _leb128(data, at + 1 + extension)
        if start + size > len(data):
            raise MsgError("not an AV1 bitstream (OBU past the end)")
        if obu_type == 1:
            sequence = True
        elif obu_type in (3, 6) and size:  # frame header / frame: show_existing_frame, frame_type (0: KEY)
            first = data[start]
            key = key or (not first & 0x80 and (first >> 5) & 3 == 0)
        at = start + size
    return sequence and key


def _vp9_keyframe(data: bytes) -> bool:
    if not data or data[0] >> 6 != 0b10:
        raise MsgError("not a VP9 bitstream (bad frame marker)")
    bits = [(byte >> (7 - i)) & 1 for byte in data[:2] for i in range(8)]  # frame_marker, profile, ...
    profile = bits[2] | (bits[3] << 1)
    at = 5 if profile == 3 else 4
    if bits[at]:  # show_existing_frame
        return False
    return bits[at + 1] == 0


def is_keyframe(codec: Codec, data: bytes) -> bool:
    """Whether ``data`` (one sample) starts a stream: an IDR with its SPS (H.264), an IRAP (H.265), a key frame
    with its sequence header (AV1) or a VP9 key frame. MsgError when it is not a well-formed sample of ``codec``."""
    if len(data) < 2:
        raise MsgError(f"{len(data)}-byte {codec} sample")
    if codec == "H264":
        types = {h & 0x1F for h in _annexb_units(data)}
        return 5 in types and 7 in types
    if codec == "H265":
        return any(16 <= (h >> 1) & 0x3F <= 21 for h in _annexb_units(data))
    if codec == "AV1":
        return _av1_keyframe(data)
    return _vp9_keyframe(data)


def decode_compressed_video(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A ``foxglove_msgs/CompressedVideo``: its sample as it is (h264, h265, av1, vp9)."""
    msg = deserialize(data, "foxglove_msgs/msg/CompressedVideo")
    codec = video_codec(str(msg.format))
    if codec is None:
        raise MsgError(f"CompressedVideo format {str(msg.format)[:40]!r} is none of h264, h265, av1, vp9")
    sample = bytes(msg.data)
    stamp = int(msg.timestamp.sec) * 1_000_000_000 + int(msg.timestamp.nanosec)
    keyframe = is_keyframe(codec, sample)
    return Decoded(str(msg.frame_id).lstrip("/"), stamp, (VideoSample(codec, sample, keyframe),))


def video_sample(fmt: str, blob: bytes) -> VideoSample:
    """The sample of a ``CompressedImage`` whose ``format`` names a video codec."""
    codec = video_codec(fmt)
    assert codec is not None
    return VideoSample(codec, blob, is_keyframe(codec, blob))


@dataclass
class VideoEncoder:
    """One camera topic's encoder: :meth:`encode` takes its images in time order and gives one sample each."""

    codec: EncoderName = "av1"
    live: bool = False
    keyint_s: float = 2.0
    notes: list[str] = field(default_factory=list)
    """Said by the caller, once each: a size change, an image it does not take."""
    refused: str | None = None
    """Why the topic stays lossless (the encoding or size the encoder does not take), once refused."""
    _context: Any = field(default=None, init=False)
    _size: tuple[int, int] | None = field(default=None, init=False)
    _frames: int = field(default=0, init=False)
    _last_key_ns: int | None = field(default=None, init=False)

    def takes(self, image: Image) -> bool:
        """Whether ``image`` is encoded (False: logged lossless); the first refusal is noted."""
        if self.refused is not None:
            return False
        if image.encoding not in VIDEO_ENCODINGS:
            if image.encoding in ("8SC1",):
                self.refused = f"encoding {image.encoding} is not encoded as video"
                self.notes.append(f"{self.refused}; the topic stays lossless")
            return False
        height, width = image.pixels.shape[:2]
        if width % 2 or height % 2 or width < 16 or height < 16:
            self.refused = f"{width}x{height} images (odd or tiny) are not encoded as video"
            self.notes.append(f"{self.refused}; the topic stays lossless")
            return False
        return True

    def _open(self, width: int, height: int) -> Any:
        av = load_av()
        name = "libsvtav1" if self.codec == "av1" else "libx264"
        context = av.CodecContext.create(name, "w")
        context.width, context.height, context.pix_fmt = width, height, "yuv420p"
        context.time_base, context.framerate = Fraction(1, 30), Fraction(30)
        context.max_b_frames = 0
        context.gop_size = int(30 * self.keyint_s)
        if self.codec == "av1":  # low delay: no reordering; preset 12 (mapped to 11), the fastest
            params = "pred-struct=1" + (":rc=2" if self.live else "")
            options = {"preset": "12", "svtav1-params": params}
        else:
            options = {"preset": "veryfast", "tune": "zerolatency", "bf": "0", "forced-idr": "1"}
        if self.live:
            context.bit_rate = LIVE_BITRATE
            if self.codec == "h264":
                options |= {"maxrate": str(LIVE_BITRATE), "bufsize": str(LIVE_BITRATE // 2)}
        else:
            options["crf"] = str(CRF[self.codec])
        context.options = options
        return context

    def close(self) -> int:
        """End the stream (the encoder is drained); how many frames it still held (dropped: none, low delay)."""
        if self._context is None:
            return 0
        held = len(self._context.encode(None))
        self._context = self._size = None
        return held

    def encode(self, image: Image, time_ns: int) -> list[VideoSample]:
        """``image`` (one :meth:`takes`) as samples: one, or none while the encoder holds it back."""
        av = load_av()
        pixels: np.ndarray = image.pixels
        height, width = pixels.shape[:2]
        if self._size != (width, height):
            if self._size is not None:
                self.notes.append(
                    f"the image size changed from {self._size[0]}x{self._size[1]} to {width}x{height}: "
                    "a new stream from a keyframe"
                )
            self.close()
            self._context, self._size, self._last_key_ns = self._open(width, height), (width, height), None
        frame = av.VideoFrame.from_ndarray(pixels, format=PIXEL_FORMATS[image.color_model])
        frame.pts = self._frames
        self._frames += 1
        if self._last_key_ns is None or time_ns - self._last_key_ns >= self.keyint_s * 1e9 * 0.999:
            frame.pict_type = av.video.frame.PictureType.I
            self._last_key_ns = time_ns
        codec: Codec = "AV1" if self.codec == "av1" else "H264"
        return [VideoSample(codec, bytes(p), bool(p.is_keyframe)) for p in self._context.encode(frame)]
