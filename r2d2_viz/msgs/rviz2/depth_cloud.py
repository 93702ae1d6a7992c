"""A depth image and its camera's intrinsics as RViz's DepthCloud display turns them into points: each pixel
``(u, v)`` with a valid depth ``d`` (m) → ``((u - cx) d / fx, (v - cy) d / fy, d)`` in the depth image's (optical)
frame, coloured by the pixel of an RGB image of the same size when there is one, else white.

Transcribed from ``rviz_common/src/rviz_common/depth_cloud_mld.cpp`` (``MultiLayerDepth``): the projection uses the
CameraInfo's ``P`` — ``fx = P[0] · s_x``, ``fy = P[5] · s_y``, ``cx = (P[2] - roi.x_offset) · s_x``,
``cy = (P[6] - roi.y_offset) · s_y``, ``s = 1 / binning`` when binning > 1 — and ``DepthTraits``: a 16UC1 depth
is millimetres (0: no depth), a 32FC1 one metres (any finite value, 0 included). Vectorised numpy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from r2d2_viz.msgs.shapes import F32, U8, Image, Points
from r2d2_viz.msgs.typestore import MsgError

DEPTH_ENCODINGS = ("16UC1", "mono16", "32FC1")
WHITE = np.array([[255, 255, 255, 255]], dtype=np.uint8)
POINT_RADIUS = 0.005
"""RViz's DepthCloud draws 1 cm points (Style Flat Squares, Auto Size off)."""


@dataclass(frozen=True)
class Projection:
    """``MultiLayerDepth``'s projection constants (float32, as RViz keeps them)."""

    cx: float
    cy: float
    fx: float
    fy: float


def projection_of(info: Any) -> Projection:
    """A deserialised CameraInfo's projection; refused when ``P`` has no focal length or is not finite."""
    p = np.asarray(info.p, dtype=np.float64)
    if not np.all(np.isfinite(p)) or p[0] == 0 or p[5] == 0:
        raise MsgError("camera info without a usable projection P")
    sx = 1.0 / int(info.binning_x) if int(info.binning_x) > 1 else 1.0
    sy = 1.0 / int(info.binning_y) if int(info.binning_y) > 1 else 1.0
    return Projection(
        float(np.float32((p[2] - int(info.roi.x_offset)) * sx)),
        float(np.float32((p[6] - int(info.roi.y_offset)) * sy)),
        p[0] * sx,
        p[5] * sy,
    )


def rgba_of(image: Image) -> U8:
    """An RGB(A)/BGR(A) 8-bit image as RGBA8 rows ``(H·W, 4)`` (alpha 255), or mono as grey."""
    px = np.asarray(image.pixels)
    if px.dtype != np.uint8:
        raise MsgError(f"colour image {image.encoding}: 8-bit colour only")
    h, w = px.shape[:2]
    out = np.full((h * w, 4), 255, dtype=np.uint8)
    flat = px.reshape(h * w, -1)
    if flat.shape[1] == 1:
        out[:, :3] = flat
    else:
        order = [2, 1, 0] if image.color_model.startswith("BGR") else [0, 1, 2]
        out[:, :3] = flat[:, order]
    return out


def depth_points(
    depth: Image, projection: Projection, color: Image | None = None, radius: float = POINT_RADIUS
) -> Points:
    """The points of ``depth`` (its pixels ``(H, W)``), coloured by ``color`` when it has the same size."""
    raw: npt.NDArray[np.generic] = np.asarray(depth.pixels)
    if raw.ndim != 2 or depth.encoding not in DEPTH_ENCODINGS:
        raise MsgError(f"depth image {depth.encoding!r}: DepthCloud takes 16UC1 or 32FC1")
    h, w = raw.shape
    if raw.dtype == np.uint16:
        valid = raw != 0
        metres = raw.astype(np.float32) * np.float32(0.001)
    else:
        metres = raw.astype(np.float32)
        valid = np.isfinite(metres)
    f32 = np.float32
    px = (np.arange(w, dtype=f32) - f32(projection.cx)) * f32(1.0 / projection.fx)
    py = (np.arange(h, dtype=f32) - f32(projection.cy)) * f32(1.0 / projection.fy)
    vs, us = np.nonzero(valid)
    d = metres[vs, us]
    with np.errstate(all="ignore"):  # a hostile 3e38 m depth: inf, silently (as the registry's decoders)
        positions: F32 = np.stack([px[us] * d, py[vs] * d, d], axis=1).astype(np.float32)
    colors = WHITE
    if color is not None and np.asarray(color.pixels).shape[:2] == (h, w):
        colors = rgba_of(color)[vs * w + us]
    return Points(positions, colors, radius)
