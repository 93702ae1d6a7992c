"""Rigid-transform maths in plain numpy, vectorised over leading axes.

Quaternions are stored ``xyzw`` (Rerun's order) everywhere in this project.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from r2d2_viz.arrays import F64


def quat_from_axis_angle(axis: npt.ArrayLike, angle: npt.ArrayLike) -> F64:
    """``xyzw`` quaternions for rotations by ``angle`` (shape ``(...)``) about unit ``axis`` (3,)."""
    half = 0.5 * np.asarray(angle, dtype=np.float64)
    s = np.sin(half)
    out = np.empty((*half.shape, 4))
    out[..., :3] = s[..., None] * np.asarray(axis, dtype=np.float64)
    out[..., 3] = np.cos(half)
    return out


def quat_multiply(a: npt.ArrayLike, b: npt.ArrayLike) -> F64:
    """Hamilton product ``a ⊗ b`` of ``xyzw`` quaternions (broadcasting)."""
    ax, ay, az, aw = np.moveaxis(np.asarray(a, dtype=np.float64), -1, 0)
    bx, by, bz, bw = np.moveaxis(np.asarray(b, dtype=np.float64), -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def quat_to_matrix(q: npt.ArrayLike) -> F64:
    """3×3 rotation matrices from (not necessarily unit) ``xyzw`` quaternions; an all-zero or non-finite one (a
    lying message) gives a NaN matrix, silently: callers drop non-finite poses, numpy prints nothing."""
    unit = np.asarray(q, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        unit = unit / np.linalg.norm(unit, axis=-1, keepdims=True)
    x, y, z, w = np.moveaxis(unit, -1, 0)
    out = np.empty((*unit.shape[:-1], 3, 3))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - z * w)
    out[..., 0, 2] = 2 * (x * z + y * w)
    out[..., 1, 0] = 2 * (x * y + z * w)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - x * w)
    out[..., 2, 0] = 2 * (x * z - y * w)
    out[..., 2, 1] = 2 * (y * z + x * w)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def matrix_to_quat(R: npt.ArrayLike) -> F64:
    """``xyzw`` unit quaternions (w ≥ 0) from 3×3 rotation matrices, robust near 180° (Shepperd)."""
    matrices = np.asarray(R, dtype=np.float64)
    m = matrices.reshape(-1, 3, 3)
    trace = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    # Four candidate forms; pick, per matrix, the one with the largest pivot.
    cands = np.stack(
        [
            np.stack([m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1], 1 + trace], -1),
            np.stack(
                [1 + 2 * m[:, 0, 0] - trace, m[:, 0, 1] + m[:, 1, 0], m[:, 0, 2] + m[:, 2, 0], m[:, 2, 1] - m[:, 1, 2]],
                -1,
            ),
            np.stack(
                [m[:, 0, 1] + m[:, 1, 0], 1 + 2 * m[:, 1, 1] - trace, m[:, 1, 2] + m[:, 2, 1], m[:, 0, 2] - m[:, 2, 0]],
                -1,
            ),
            np.stack(
                [m[:, 0, 2] + m[:, 2, 0], m[:, 1, 2] + m[:, 2, 1], 1 + 2 * m[:, 2, 2] - trace, m[:, 1, 0] - m[:, 0, 1]],
                -1,
            ),
        ],
        axis=1,
    )
    pivots = np.stack(
        [1 + trace, 1 + 2 * m[:, 0, 0] - trace, 1 + 2 * m[:, 1, 1] - trace, 1 + 2 * m[:, 2, 2] - trace], -1
    )
    q = cands[np.arange(len(m)), np.argmax(pivots, axis=1)]
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q *= np.where(q[:, 3:4] < 0, -1.0, 1.0)
    out: F64 = q.reshape(*matrices.shape[:-2], 4)
    return out
