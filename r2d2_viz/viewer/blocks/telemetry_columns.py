"""Blocks of display messages (:class:`~r2d2_viz.sources.topic_blocks.TopicBlock`, issue 46) straight to Rerun
columns: the rows logging each message would make (:func:`r2d2_viz.viewer.displays.log_decoded` through
:class:`~r2d2_viz.viewer.blocks.row_columns.RowColumns`), built from the block's arrays with no Python object per
message.

An Imu block makes, as its messages one by one would: on ``<topic>``, for each message whose orientation is drawn,
``CoordinateFrame`` (its frame), ``Arrows3D`` (the x, y, z axes from the origin, 1 cm radius, red, green, blue) and
``InstancePoses3D`` (identity); on ``<topic>/angular_velocity`` and ``<topic>/linear_acceleration`` a ``Scalars``
row of x, y, z for every message (their ``SeriesLines`` names static, once). :class:`BlockRuns` holds each
entity's rows across blocks (up to :data:`~r2d2_viz.viewer.blocks.row_columns.RUN_ROWS`) and sends them as one
``send_columns``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.msgs.blocks.telemetry_blocks import ImuBlock
from r2d2_viz.msgs.telemetry import AXIS_COLORS
from r2d2_viz.sources.topic_blocks import TopicBlock
from r2d2_viz.viewer.blocks.plain_log import PlainBook
from r2d2_viz.viewer.blocks.row_columns import RUN_ROWS
from r2d2_viz.viewer.columns import send, time_array
from r2d2_viz.viewer.displays import Clock, packed

_F32 = pa.float32()
_AXIS_RADIUS = 0.01
"""The Imu's arrows' radius (:func:`r2d2_viz.msgs.telemetry.decode_imu`)."""
_XYZ = ("x", "y", "z")


@dataclass
class _Run:
    """One entity's rows not sent yet: per piece, its times and, per column, its values and each row's count."""

    descriptors: tuple[rr.ComponentDescriptor, ...]
    times: list[np.ndarray] = field(default_factory=list)
    values: list[list[pa.Array]] = field(default_factory=list)
    counts: list[list[np.ndarray]] = field(default_factory=list)
    rows: int = 0


class BlockRuns:
    """Rows of blocks held per entity until an entity holds :data:`RUN_ROWS` or :meth:`send` is called."""

    def __init__(self, rec: rr.RecordingStream, timeline: str, clock: Clock) -> None:
        self.rec, self.timeline, self.clock = rec, timeline, clock
        self.runs: dict[str, _Run] = {}

    def add(
        self,
        entity: str,
        times_ns: np.ndarray,
        columns: list[tuple[rr.ComponentDescriptor, pa.Array, np.ndarray]],
    ) -> None:
        """Rows at ``times_ns`` on ``entity``: per column its descriptor, its instances and each row's count."""
        if not len(times_ns):
            return
        descriptors = tuple(d for d, _, _ in columns)
        run = self.runs.get(entity)
        if run is not None and run.descriptors != descriptors:
            self.send(entity)
            run = None
        if run is None:
            run = self.runs[entity] = _Run(descriptors, values=[[] for _ in columns], counts=[[] for _ in columns])
        run.times.append(times_ns)
        for values, counts, (_, array, count) in zip(run.values, run.counts, columns, strict=True):
            values.append(array)
            counts.append(count)
        run.rows += len(times_ns)
        if run.rows >= RUN_ROWS:
            self.send(entity)

    def send(self, *entities: str) -> None:
        """Send the runs of ``entities`` and of the entities below them (every run when none is named)."""
        below = tuple(e + "/" for e in entities)
        names = [e for e in self.runs if e in entities or e.startswith(below)] if entities else list(self.runs)
        for name in names:
            run = self.runs.pop(name)
            times = time_array(np.concatenate(run.times), self.clock)
            columns = [
                (d, _lists(pa.concat_arrays(v) if len(v) > 1 else v[0], np.concatenate(c)))
                for d, v, c in zip(run.descriptors, run.values, run.counts, strict=True)
            ]
            send(self.rec, name, self.timeline, times, columns)


def _lists(values: pa.Array, counts: np.ndarray) -> pa.Array:
    """``values`` cut into a list a row of ``counts``: a component column (as row_columns builds one)."""
    offsets = np.zeros(len(counts) + 1, dtype=np.int32)
    np.cumsum(counts, out=offsets[1:])
    return pa.Array.from_buffers(pa.list_(values.type), len(counts), [None, pa.py_buffer(offsets)], children=[values])


def _vectors(values: np.ndarray, size: int, item: pa.DataType = _F32) -> pa.Array:
    """Rows of ``size`` numbers as Rerun's fixed-size lists of non-null items (Vec3D, Quaternion …)."""
    dtype = np.float32 if item == _F32 else np.float64
    flat = pa.array(np.ascontiguousarray(values, dtype=dtype).reshape(-1), type=item)
    return pa.FixedSizeListArray.from_arrays(flat, type=pa.list_(pa.field("item", item, nullable=False), size))


def _each(n: int, count: int) -> np.ndarray:
    return np.full(n, count, dtype=np.int64)


def imu_rows(runs: BlockRuns, entity: str, block: TopicBlock, plain: PlainBook) -> None:
    """An Imu block's rows (see the module's doc); ``plain``: its topic's book (series names logged once)."""
    imu = block.block
    assert isinstance(imu, ImuBlock)
    drawn, axes = imu.axes()
    m = len(axes)
    if m:
        names = np.array(imu.frames, dtype=object)  # (Arrow's take would import pyarrow.compute: ~0.5 s)
        frames = pa.array(names[imu.frame_index[drawn]], type=pa.utf8())
        colors = np.tile(packed(AXIS_COLORS), m)
        identity = np.tile([0.0, 0.0, 0.0, 1.0], (m, 1))  # Pose(): no translation, xyzw (0, 0, 0, 1)
        poses = [
            (rr.InstancePoses3D.descriptor_translations(), _vectors(np.zeros((m, 3)), 3), _each(m, 1)),
            (rr.InstancePoses3D.descriptor_quaternions(), _vectors(identity, 4), _each(m, 1)),
        ]
        runs.add(
            entity,
            block.times_ns[drawn],
            [
                (rr.CoordinateFrame.descriptor_frame(), frames, _each(m, 1)),
                (rr.Arrows3D.descriptor_vectors(), _vectors(axes.reshape(-1, 3), 3), _each(m, 3)),
                (rr.Arrows3D.descriptor_origins(), _vectors(np.zeros((3 * m, 3)), 3), _each(m, 3)),
                (rr.Arrows3D.descriptor_radii(), pa.array(np.full(m, _AXIS_RADIUS, np.float32)), _each(m, 1)),
                (rr.Arrows3D.descriptor_colors(), pa.array(colors, type=pa.uint32()), _each(m, 3)),
                *poses,
            ],
        )
    n = len(block)
    for name, values in (("angular_velocity", imu.angular_velocity), ("linear_acceleration", imu.linear_acceleration)):
        series = f"{entity}/{name}"
        if series not in plain.styled:
            plain.styled.add(series)
            runs.rec.log(series, rr.SeriesLines(names=list(_XYZ)), static=True)
        scalars = pa.array(np.ascontiguousarray(values, dtype=np.float64).reshape(-1), type=pa.float64())
        runs.add(series, block.times_ns, [(rr.Scalars.descriptor_scalars(), scalars, _each(n, 3))])


ROWS = {"sensor_msgs/msg/Imu": imu_rows}
"""Message type → what logs its blocks (the types of :data:`r2d2_viz.msgs.registry.BLOCK_DECODERS`)."""
