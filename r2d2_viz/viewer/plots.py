"""Joint plots and limits: what ``ros2 topic echo /joint_states`` would print, drawn.

* ``/joints/limited`` — values of the joints with limits, one series each; ``/joints/limited/limits`` their
  lower and upper limits, two series per joint (one entity: a row for every limit line is one chunk);
* ``/joints/continuous`` — values of continuous joints (they grow without bound: their own plot).

Values outside the URDF limits are shown, not clamped (like robot_state_publisher), and reported once per joint.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import numpy.typing as npt
import pyarrow as pa
import rerun as rr

from r2d2_viz.arrays import F64
from r2d2_viz.kinematics.tree import KinematicTree
from r2d2_viz.sources.base import Clock
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.columns import Encoded, encoded, flat_array, list_column, send, time_array


class JointPlots:
    """Series styles, per-sample plot columns, limit lines and out-of-limit checks for one robot."""

    def __init__(self, tree: KinematicTree, *, timeline: str, clock: Clock, robot: str = "") -> None:
        self.tree, self.timeline, self.clock = tree, timeline, clock
        root = entities.joints_root(robot)
        self.limits_entity = entities.LIMITS if not robot.strip("/") else f"{root}/limited/limits"
        self.limits = tree.limits
        limited = [m for m, name in enumerate(tree.moving) if name in self.limits]
        continuous = [m for m, name in enumerate(tree.moving) if name not in self.limits]
        self.series = [
            (entity, np.array(ms, dtype=np.intp))
            for entity, ms in (
                (entities.JOINTS_LIMITED if not robot.strip("/") else f"{root}/limited", limited),
                (entities.JOINTS_CONTINUOUS if not robot.strip("/") else f"{root}/continuous", continuous),
            )
            if ms
        ]
        """Each plot entity and the moving joints (columns of the values) it shows."""
        self._limited = np.array(limited, dtype=np.intp)
        self._lower = np.array([self.limits[tree.moving[m]][0] for m in limited])
        self._upper = np.array([self.limits[tree.moving[m]][1] for m in limited])
        bounds = [bound for m in limited for bound in self.limits[tree.moving[m]]]
        self._limit_row = encoded(rr.Scalars.columns(scalars=bounds).partition([len(bounds)]))
        self._reported: set[int] = set()

    def log_styles(self, rec: rr.RecordingStream) -> None:
        palette = _palette(len(self.tree.moving))
        for entity, ms in self.series:
            rec.log(
                entity,
                rr.SeriesLines(
                    colors=[palette[m] for m in ms], names=[self.tree.moving[m] for m in ms], widths=[2.0] * len(ms)
                ),
                static=True,
            )
        if len(self._limited):  # lower, upper for each joint, in the order of the limit row
            names = [self.tree.moving[m] for m in self._limited]
            rec.log(
                self.limits_entity,
                rr.SeriesLines(
                    colors=[(*palette[m][:3], 140) for m in self._limited for _ in range(2)],
                    names=[f"{name} {bound} limit" for name in names for bound in ("lower", "upper")],
                    widths=[1.0] * (2 * len(names)),
                ),
                static=True,
            )

    def encode(self, values: F64) -> list[tuple[str, Encoded]]:
        """One row per sample on each plot entity: the row of its joints' values, as ``rr.Scalars.columns``
        partitioned by sample builds it, from buffers (issue 38)."""
        descriptor, list_type = _scalars_layout()
        out: list[tuple[str, Encoded]] = []
        for entity, ms in self.series:
            if len(ms) == values.shape[1] and (ms == np.arange(len(ms))).all():  # every joint, in order: no gather
                block = np.ascontiguousarray(values, dtype=np.float64)
            else:
                block = np.ascontiguousarray(values[:, ms], dtype=np.float64)
            out.append((entity, [(descriptor, list_column(list_type, flat_array(block), len(ms)))]))
        return out

    def log_limits(self, rec: rr.RecordingStream, time_ns: int) -> None:
        """One row on every limit line at ``time_ns``: one chunk, encoded once (a robot with a thousand limited
        joints has two thousand lines; a chunk per line made the cost of a sample grow with their square)."""
        if len(self._limited):
            times = time_array(np.array([time_ns], dtype=np.int64), self.clock)
            send(rec, self.limits_entity, self.timeline, times, self._limit_row)

    def outside(self, values: F64) -> dict[int, int]:
        """Each limited joint not yet reported that leaves its limits in ``values`` → the first sample (a row
        of ``values``) it is outside. Vectorised; :meth:`reported` marks it done."""
        if not len(self._limited) or len(self._reported) == len(self._limited):
            return {}
        block = values[:, self._limited]
        out: npt.NDArray[np.bool_] = (block < self._lower) | (block > self._upper)  # (n, limited)
        first = {int(self._limited[j]): int(out[:, j].argmax()) for j in np.flatnonzero(out.any(axis=0))}
        return {m: k for m, k in first.items() if m not in self._reported}

    def out_of_limits_message(self, m: int, value: float, t_s: float) -> str:
        self._reported.add(m)
        name = self.tree.moving[m]
        lower, upper = self.limits[name]
        return (
            f"joint {name!r} left its URDF limits [{lower:g}, {upper:g}] at t={t_s:.3f} s "
            f"(value {value:.4g}); shown unclamped, like robot_state_publisher"
        )


def _palette(n: int) -> list[tuple[int, int, int, int]]:
    """Distinct, bright colours for the joint plot (golden-angle hues)."""
    colors = []
    for i in range(n):
        h = (i * 0.381966) % 1.0
        r, g, b = (0.5 + 0.5 * math.cos(2 * math.pi * (h + k / 3)) for k in (0, 1, 2))
        colors.append((int(60 + 195 * r), int(60 + 195 * g), int(60 + 195 * b), 255))
    return colors


@cache
def _scalars_layout() -> tuple[rr.ComponentDescriptor, pa.DataType]:
    """Rerun's descriptor and Arrow list type of a ``Scalars`` column, from its own builder."""
    ((descriptor, array),) = encoded(rr.Scalars.columns(scalars=[0.0]))
    return descriptor, array.type
