"""sensor_msgs Image (a numpy view honouring ``step``), CompressedImage and CameraInfo."""

from __future__ import annotations

from typing import Literal

import numpy as np

from r2d2_viz.msgs.geometry import header_of
from r2d2_viz.msgs.shapes import CompressedImage, Decoded, DecodeOptions, Image, Pinhole
from r2d2_viz.msgs.typestore import MsgError, deserialize
from r2d2_viz.msgs.video import video_codec, video_sample

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


def decode_image(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """The pixels ``(H, W)`` or ``(H, W, C)`` of an Image, row padding (``step``) removed, native byte order."""
    msg = deserialize(data, "sensor_msgs/msg/Image")
    frame, stamp = header_of(msg)
    spec = ENCODINGS.get(str(msg.encoding))
    if spec is None:
        raise MsgError(f"unsupported image encoding {msg.encoding!r}")
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
    image = Image(pixels[:, :, 0] if channels == 1 else pixels, model, str(msg.encoding))
    return Decoded(frame, stamp, (image,))


def media_type(blob: bytes, fmt: str) -> str:
    """``image/jpeg`` or ``image/png`` from the file's magic bytes (the ``format`` string as a fallback)."""
    if blob.startswith(b"\xff\xd8\xff"):
        return "image/jpeg"
    if blob.startswith(b"\x89PNG\r\n\x1a\n"):
        return "image/png"
    raise MsgError(f"compressed image is neither JPEG nor PNG (format {fmt[:40]!r})")


def decode_compressed_image(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """A CompressedImage's JPEG or PNG bytes, or its video sample when its format names a video codec
    (:mod:`r2d2_viz.msgs.video`); ``compressedDepth`` and other formats are refused."""
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
