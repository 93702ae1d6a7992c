"""RViz's Decay Time: a display's older messages stay drawn where they were received.

RViz transforms each cloud into the fixed frame when it arrives (``PointCloudCommon``: the cloud keeps the pose
its frame had at the message's stamp) and keeps it for the decay time. Rerun's visible time range (set in the
blueprint, :mod:`r2d2_viz.viewer.layout.blueprint`) shows the rows of the last N seconds, but places every row
with its entity's transforms at the time cursor, the item poses too: a moving sensor's older scans would all be
drawn where the sensor is now. So a decayed topic's points, lines and arrows are logged with their coordinates
already in the fixed frame (looked up in the recorded transforms at the message's stamp); a message whose frame
the transforms do not place yet is logged in its own frame, as any other.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from r2d2_viz.arrays import F64
from r2d2_viz.kinematics.transforms import quat_to_matrix
from r2d2_viz.msgs.shapes import IDENTITY, Arrows, Decoded, LineStrips, Points, Pose, Shape
from r2d2_viz.sources.base import TfRecords
from r2d2_viz.sources.tf_lookup import TfLookup

HISTORY_NS = 10 * 1_000_000_000
"""Moving transforms kept for placing: messages are placed as they are read, at most this long after their TF."""


class FixedFramePlacer:
    """Puts a decoded message's points, lines and arrows into the fixed frame, at the message's stamp."""

    def __init__(self, records: Sequence[TfRecords], fixed: str) -> None:
        self._records = [r for r in records if len(r)]
        self.lookup = TfLookup(self._records)
        self.fixed = fixed

    def add(self, records: TfRecords) -> None:
        """Transforms a replay just read (static ones kept; moving ones for the last HISTORY_NS)."""
        latest = int(records.times_ns.max())
        self._records = [r for r in self._records if r.static or int(r.times_ns.max()) >= latest - HISTORY_NS] + [
            records
        ]
        self.lookup = TfLookup(self._records)

    def place(self, decoded: Decoded, time_ns: int) -> Decoded:
        frame = decoded.frame_id
        movable = (Points, LineStrips, Arrows)
        if not frame or frame == self.fixed or not all(isinstance(i, movable) for i in decoded.items):
            return decoded
        pose = self.lookup.pose(self.fixed, frame, np.array([decoded.stamp_ns or time_ns], dtype=np.int64))
        if pose is None:
            return decoded
        items = tuple(_moved(item, pose[0][0], quat_to_matrix(pose[1][0])) for item in decoded.items)
        return dataclasses.replace(decoded, frame_id=self.fixed, items=items)


def _matrix(pose: Pose) -> tuple[F64, F64]:
    return np.asarray(pose.translation, dtype=np.float64), quat_to_matrix(np.asarray(pose.xyzw, dtype=np.float64))


def _moved(item: Shape, t_fixed_frame: F64, R_fixed_frame: F64) -> Shape:
    """``item`` with its coordinates in the fixed frame: ``T_fixed_frame ∘ T_frame_item`` applied to them."""
    t_item, R_item = _matrix(getattr(item, "T_frame_item", IDENTITY))
    R = R_fixed_frame @ R_item
    t = R_fixed_frame @ t_item + t_fixed_frame

    def points(p: np.ndarray) -> np.ndarray:
        return (np.asarray(p, dtype=np.float64) @ R.T + t).astype(np.float32)

    if isinstance(item, Points):
        return dataclasses.replace(item, positions=points(item.positions), T_frame_item=IDENTITY)
    if isinstance(item, LineStrips):
        return dataclasses.replace(item, strips=tuple(points(s) for s in item.strips), T_frame_item=IDENTITY)
    assert isinstance(item, Arrows)
    vectors = (np.asarray(item.vectors, dtype=np.float64) @ R.T).astype(np.float32)
    return dataclasses.replace(item, origins=points(item.origins), vectors=vectors, T_frame_item=IDENTITY)
