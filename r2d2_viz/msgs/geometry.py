"""Small helpers shared by the decoders: headers, poses, quaternions (``xyzw``), colours, covariances."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from r2d2_viz.msgs.shapes import F32, U8, Ellipsoids, Pose, Rgba8
from r2d2_viz.msgs.typestore import MsgError

F64 = npt.NDArray[np.float64]
FLOAT32_MAX = float(np.finfo(np.float32).max)
"""Beyond this a double turns infinite where the viewer draws it (float32): such a vector is refused like NaN."""


def frame_of(frame_id: str) -> str:
    """A frame id as tf2 keys it: one leading '/' dropped."""
    return frame_id[1:] if frame_id.startswith("/") else frame_id


def header_of(msg: Any) -> tuple[str, int]:
    """``(frame_id, stamp_ns)`` of a message with a ``header``."""
    stamp = msg.header.stamp
    return frame_of(msg.header.frame_id), int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def xyz(v: Any) -> tuple[float, float, float]:
    """A Point / Vector3 as a tuple; values that are not finite as float32 (NaN, ±inf, |v| > 3.4e38) are refused."""
    out = (float(v.x), float(v.y), float(v.z))
    if not all(abs(c) <= FLOAT32_MAX for c in out):
        raise MsgError(f"non-finite vector {out}" + ("" if not all(np.isfinite(out)) else " (in float32)"))
    return out


def xyzw(q: Any) -> tuple[float, float, float, float]:
    """A Quaternion message normalised (all zeros reads as identity, as RViz does); non-finite is refused."""
    x, y, z, w = float(q.x), float(q.y), float(q.z), float(q.w)  # plain floats: one message's, numpy costs more
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(norm):
        raise MsgError(f"non-finite quaternion {[x, y, z, w]}")
    if norm < 1e-12:
        return (0.0, 0.0, 0.0, 1.0)
    return (x / norm, y / norm, z / norm, w / norm)


def pose_of(p: Any) -> Pose:
    """A geometry_msgs/Pose as a ``Pose``."""
    return Pose(xyz(p.position), xyzw(p.orientation))


def transform_of(t: Any) -> Pose:
    """A geometry_msgs/Transform as a ``Pose``."""
    return Pose(xyz(t.translation), xyzw(t.rotation))


def quat_matrix(q: Sequence[float]) -> F64:
    """The rotation matrix of a unit quaternion ``xyzw``."""
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_quat(R: F64) -> tuple[float, float, float, float]:
    """The unit quaternion ``xyzw`` of a rotation matrix (Shepperd's method)."""
    m = R
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s]
    v = np.array(q) / np.linalg.norm(q)
    return (float(v[0]), float(v[1]), float(v[2]), float(v[3]))


def rotate(q: Sequence[float], v: F64) -> F64:
    """Vectors ``v (N, 3)`` rotated by the quaternion ``xyzw``."""
    return np.asarray(v, dtype=np.float64) @ quat_matrix(q).T


def rgba8(c: Any) -> Rgba8:
    """A std_msgs/ColorRGBA (floats 0..1) as 8-bit RGBA; NaN reads as 0."""
    r, g, b, a = (0 if v != v else round(min(max(float(v), 0.0), 1.0) * 255) for v in (c.r, c.g, c.b, c.a))
    return (r, g, b, a)  # (round: half to even, as numpy's)


def colors8(colors: Sequence[Any]) -> U8:
    """A list of std_msgs/ColorRGBA as an ``(N, 4)`` RGBA8 array."""
    v = np.array([[c.r, c.g, c.b, c.a] for c in colors], dtype=np.float64).reshape(-1, 4)
    return np.round(np.clip(np.nan_to_num(v, nan=0.0), 0.0, 1.0) * 255).astype(np.uint8)


def one_color(c: Rgba8) -> U8:
    """One colour for all instances, ``(1, 4)``."""
    return np.array([c], dtype=np.uint8)


def points3(points: Sequence[Any]) -> F32:
    """A list of geometry_msgs/Point (or Point32) as ``(N, 3)`` float32."""
    return np.array([[p.x, p.y, p.z] for p in points], dtype=np.float32).reshape(-1, 3)


def covariance_ellipsoid(cov6: npt.ArrayLike, pose: Pose, scale: float, color: Rgba8) -> Ellipsoids:
    """The position block (top-left 3x3, in the header frame) of a 6x6 covariance as an ellipsoid centred on
    ``pose``: axes the eigenvectors, half sizes ``scale * sqrt(eigenvalue)`` (1 sigma at scale 1, RViz's default).
    A non-finite covariance gives an empty ``Ellipsoids``."""
    cov = np.asarray(cov6, dtype=np.float64).reshape(6, 6)[:3, :3]
    empty = Ellipsoids(
        np.zeros((0, 3), np.float32), np.zeros((0, 3), np.float32), np.zeros((0, 4), np.float32), one_color(color)
    )
    if not np.all(np.isfinite(cov)):
        return empty
    sym = (cov + cov.T) / 2
    values, vectors = np.linalg.eigh(sym)
    if np.linalg.det(vectors) < 0:
        vectors[:, 2] = -vectors[:, 2]
    half = scale * np.sqrt(np.clip(values, 0.0, None))
    return Ellipsoids(
        centers=np.array([pose.translation], dtype=np.float32),
        half_sizes=half.reshape(1, 3).astype(np.float32),
        xyzw=np.array([matrix_quat(vectors)], dtype=np.float32),
        colors=one_color(color),
    )


def pose_arrows(poses: Sequence[Pose], length: float) -> tuple[F32, F32]:
    """Origins and vectors of arrows along each pose's x axis, ``length`` m long."""
    origins = np.array([p.translation for p in poses], dtype=np.float64).reshape(-1, 3)
    vectors = np.array([quat_matrix(p.xyzw)[:, 0] * length for p in poses], dtype=np.float64).reshape(-1, 3)
    return origins.astype(np.float32), vectors.astype(np.float32)
