"""Which Odometry messages RViz's Odometry display keeps, applied before a pose takes a slot of its history
(``<topic>/<k>``): a pose is dropped when it lies within the Position Tolerance *and* the Angle Tolerance of the last
pose kept (``OdometryDisplay::messageIsSimilarToPrevious``,
rviz_default_plugins/src/rviz_default_plugins/displays/odometry/odometry_display.cpp; the angle is
``ogreQuaternionAngularDistance`` of quaternion_helper.hpp), so a stopped robot leaves one arrow, not one per
message. Both compare in float, as Ogre does: ``|last − current| < position_tolerance`` and
``2·atan2(|im(last · conj(current))|, |re(…)|) < angle_tolerance``; either reaching its tolerance keeps the pose.

A replay's due messages go a block at once (their poses read from the bytes by
:func:`r2d2_viz.msgs.layouts.odometry_poses` and compared with numpy, :func:`kept`: 2–11 µs a pose on a block,
whether the robot stands, moves a tolerance a message or keeps a pose every 20), a live message alone (~0.1 ms):
each topic's last pose kept carries over, so the same poses are kept either way. Pure numpy.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from r2d2_viz.arrays import F64
from r2d2_viz.msgs.layouts import odometry_poses
from r2d2_viz.sources.bag_displays import TopicMessage

POSITION_TOLERANCE = 0.1
"""RViz's Position Tolerance by default (m)."""
ANGLE_TOLERANCE = 0.1
"""RViz's Angle Tolerance by default (rad)."""
_FIRST_STRETCH = 8
_LOOKBACK = 8
"""Each pose is compared with this many before it at once (a robot moving slower than its tolerance a message
keeps a pose every few)."""


@dataclass(frozen=True)
class Tolerance:
    """How far a pose must move from the last one kept to be kept (RViz's Odometry properties)."""

    position: float = POSITION_TOLERANCE
    angle: float = ANGLE_TOLERANCE


def _product_of_conjugate(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``first * conj(second)`` as Ogre multiplies (float32): its imaginary norm and its real part. Quaternions are
    ``xyzw`` rows."""
    x1, y1, z1, w1 = (first[..., i] for i in range(4))
    x2, y2, z2, w2 = (second[..., i] for i in range(4))
    x2, y2, z2 = -x2, -y2, -z2
    w = w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2
    x = w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2
    y = w1 * y2 + y1 * w2 + z1 * x2 - x1 * z2
    z = w1 * z2 + z1 * w2 + x1 * y2 - y1 * x2
    return np.sqrt(x * x + y * y + z * z), w


def angular_distance(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """RViz's ``ogreQuaternionAngularDistance`` (float32): the angle between quaternions ``xyzw``, broadcast."""
    a, b = np.asarray(first, dtype=np.float32), np.asarray(second, dtype=np.float32)
    imaginary_norm, w = _product_of_conjugate(a, b)
    return np.asarray(np.float32(2.0) * np.arctan2(imaginary_norm, np.sqrt(w * w)))


def similar(last: np.ndarray, poses: np.ndarray, tolerance: Tolerance) -> np.ndarray:
    """Per row of ``poses`` (``(n, 7)``): whether it is within both tolerances of the pose ``last`` (one, or a row
    each) (RViz's ``messageIsSimilarToPrevious``: such a pose is dropped). In float32, as Ogre computes."""
    a, b = np.asarray(last, dtype=np.float32), np.asarray(poses, dtype=np.float32)
    d = a[..., :3] - b[:, :3]
    position_within = np.sqrt((d * d).sum(axis=1, dtype=np.float32)) < np.float32(tolerance.position)
    angle_within = angular_distance(a[..., 3:], b[:, 3:]) < np.float32(tolerance.angle)
    return np.asarray(position_within & angle_within)


def valid(poses: F64) -> np.ndarray:
    """RViz's ``messageIsValid`` on the pose: finite, and a quaternion whose squares add to 1 within 10e-3."""
    with np.errstate(invalid="ignore", over="ignore"):
        norm = (poses[:, 3:] ** 2).sum(axis=1)
        return np.asarray(np.isfinite(poses).all(axis=1) & (np.abs(norm - 1.0) < 10e-3))


def kept(poses: F64, last: F64 | None, tolerance: Tolerance) -> tuple[np.ndarray, F64 | None]:
    """Which of ``poses`` (in order) RViz keeps after ``last`` (the last pose kept before them; None: none yet),
    and the last pose kept after them. A pose that is not :func:`valid` is left to its decoder (kept, never
    compared against).

    Vectorised two ways: each pose is compared at once with each of the :data:`_LOOKBACK` poses before it (a
    moving robot keeps a pose every few: each decision is then a look-up); a pose further from the last one kept
    is compared with it, a growing stretch of poses at a time (a stopped robot: a few comparisons a block). Every
    comparison is the same float32 arithmetic, so a block's decisions do not depend on how the poses were cut into
    blocks."""
    ok = valid(poses)
    mask = ~ok
    rows = np.flatnonzero(ok)
    p = poses[rows].astype(np.float32)
    n = len(p)
    lookback = min(_LOOKBACK, n - 1)
    unlike = [[]] + [[True] * k + (~similar(p[:-k], p[k:], tolerance)).tolist() for k in range(1, lookback + 1)]
    chosen = [False] * n
    reference: int | None = None  # the last pose kept, in this block (None: before it, ``last``)
    i, stretch = 0, _FIRST_STRETCH
    if last is None and n:  # nothing kept yet: the first pose is
        chosen[0], reference, i = True, 0, 1
    while i < n:
        if reference is not None and i - reference <= lookback:
            if unlike[i - reference][i]:
                chosen[i], reference = True, i
            i += 1
            continue
        ref = p[reference] if reference is not None else np.asarray(last, dtype=np.float32)
        end = min(n, i + stretch)
        hits = np.flatnonzero(~similar(ref, p[i:end], tolerance))[:1]
        if not hits.size:
            i, stretch = end, stretch * 2
            continue
        reference = i + int(hits[0])
        chosen[reference], i, stretch = True, reference + 1, _FIRST_STRETCH
    mask[rows[np.asarray(chosen, dtype=bool)]] = True
    return mask, poses[rows[reference]] if reference is not None else last


ODOMETRY = "nav_msgs/msg/Odometry"


class OdometryKeep:
    """``tolerance``: a topic's tolerances (its display's, or RViz's defaults)."""

    def __init__(self, tolerance: Callable[[str], Tolerance]) -> None:
        self.tolerance = tolerance
        self.last: dict[str, F64 | None] = {}
        """Topic → the last pose kept."""
        self.dropped = 0

    def kept(self, messages: Sequence[TopicMessage]) -> list[TopicMessage]:
        """``messages`` (in time order) without the odometry poses RViz would not draw."""
        rows: dict[str, list[int]] = {}
        for i, message in enumerate(messages):
            if message.msgtype == ODOMETRY:
                rows.setdefault(message.topic, []).append(i)
        if not rows:
            return list(messages)
        drop: set[int] = set()
        for topic, indices in rows.items():
            poses = odometry_poses([messages[i].data for i in indices])
            mask, self.last[topic] = kept(poses, self.last.get(topic), self.tolerance(topic))
            drop.update(i for i, keep in zip(indices, mask.tolist(), strict=True) if not keep)
        self.dropped += len(drop)
        return [m for i, m in enumerate(messages) if i not in drop]
