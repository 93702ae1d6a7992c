"""Arrow columns for Rerun's ``send_columns``: built once per block of samples, sliced per send.

Rerun's ``…columns()`` builders encode a whole block at once; a live run then sends any run of its samples
by slicing those Arrow arrays (zero-copy) and handing them to the public ``rr.send_columns``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import pyarrow as pa
import rerun as rr

from r2d2_viz.arrays import I64
from r2d2_viz.sources.base import Clock

Encoded = list[tuple[rr.ComponentDescriptor, pa.Array]]


def f32(values: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """``values`` in the float32 Rerun stores positions in, cast here: a double beyond float32's range (a lying
    message, a 1e300 translation) becomes ±inf, which Rerun does not draw, silently — Rerun's own cast would
    print numpy's ``RuntimeWarning: overflow encountered in cast`` and its source line."""
    with np.errstate(over="ignore"):
        return np.asarray(values, dtype=np.float32)


def encoded(columns: rr.ComponentColumnList | list[rr.ComponentColumn]) -> Encoded:
    """Each column's descriptor and Arrow list array, encoded once."""
    return [(c.component_descriptor(), c.as_arrow_array()) for c in columns]


class _Prebuilt(rr.ComponentColumn):
    """A column whose Arrow list array is already built (by :func:`encoded`, then sliced)."""

    def __init__(self, descriptor: rr.ComponentDescriptor, array: pa.Array) -> None:  # nothing to partition
        self.descriptor = descriptor
        self._array = array

    def as_arrow_array(self) -> pa.Array:
        return self._array


class _TimeArray:
    """A time column already in Arrow (``rr.TimeColumnLike``)."""

    def __init__(self, timeline: str, times: pa.Array) -> None:
        self._timeline, self._times = timeline, times

    def timeline_name(self) -> str:
        return self._timeline

    def as_arrow_array(self) -> pa.Array:
        return self._times


def time_array(times_ns: I64, clock: Clock) -> pa.Array:
    """Nanoseconds as Rerun's duration or timestamp column type, built over a copy of their int64 buffer.

    Not ``pa.array(numpy)``: it lets go of the GIL, and a batch run's main thread then waits for the bag's reader
    thread to hand it back — up to the interpreter's switch interval (5 ms); 1.4 ms a call measured beside a busy
    thread against 4 µs from buffers (a 20 s sensor bag sends ~1,000 time columns)."""
    values = np.array(times_ns, dtype=np.int64)  # a copy: the column does not change with the caller's array
    kind = pa.duration("ns") if clock == "duration" else pa.timestamp("ns")
    return pa.Array.from_buffers(kind, len(values), [None, pa.py_buffer(values)])


def flat_array(values: npt.NDArray[np.number[Any]]) -> pa.Array:
    """Numbers (any shape) flattened as an Arrow array of their type over their buffer: what ``pa.array`` makes (NaN
    a value, not a null), built without letting go of the GIL (see :func:`time_array`)."""
    flat = np.ascontiguousarray(values).reshape(-1)
    return pa.Array.from_buffers(pa.from_numpy_dtype(flat.dtype), len(flat), [None, pa.py_buffer(flat)])


def float32_array(values: npt.NDArray[np.float32]) -> pa.Array:
    """``values`` cast to float32 (any shape), flattened: :func:`flat_array`."""
    return flat_array(np.asarray(values, dtype=np.float32))


def packed_rgba(rgb: tuple[int, int, int], n: int) -> pa.Array:
    """``n`` copies of an opaque colour as Rerun's ``Color`` values: uint32 ``0xRRGGBBAA``."""
    r, g, b = rgb
    return pa.Array.from_buffers(
        pa.uint32(), n, [None, pa.py_buffer(np.full(n, (r << 24) | (g << 16) | (b << 8) | 0xFF, dtype=np.uint32))]
    )


def send(
    rec: rr.RecordingStream,
    entity: str,
    timeline: str,
    times: pa.Array,
    columns: Encoded,
    start: int = 0,
    count: int | None = None,
) -> None:
    """``rr.send_columns`` for rows ``start … start+count-1`` of prebuilt columns (all by default)."""
    if start or (count is not None and count != len(times)):
        n = len(times) - start if count is None else count
        times = times.slice(start, n)
        columns = [(d, a.slice(start, n)) for d, a in columns]
    rr.send_columns(
        entity,
        indexes=[_TimeArray(timeline, times)],
        columns=[_Prebuilt(d, a) for d, a in columns],
        recording=rec,
    )


def tiled(texts: list[str], n: int) -> pa.StringArray:
    """``texts * n`` as an Arrow string array, built from two buffers (no per-row Python strings).

    Rerun takes an Arrow array of its own type as is; a Python list would be converted row by row.
    The column itself is unchanged: every row still holds its name."""
    data_parts = [t.encode() for t in texts]
    lengths = np.tile(np.array([len(e) for e in data_parts], dtype=np.int64), n)
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    if offsets[-1] > np.iinfo(np.int32).max:  # cannot happen for the chunk sizes used; stay correct anyway
        return pa.array(texts * n, type=pa.utf8())
    data = b"".join(data_parts) * n
    return pa.StringArray.from_buffers(len(lengths), pa.py_buffer(offsets.astype(np.int32)), pa.py_buffer(data))


def first_of_every(lists: pa.ListArray, rows: int) -> pa.ListArray:
    """``lists`` (one list per sample) spread over ``rows`` rows per sample: each sample's list on its first
    row, null on the others — a null cell is no data, so a query at that time finds the first row's."""
    if rows == 1:
        return lists
    offsets = lists.offsets.to_numpy()
    spread = np.empty(len(lists) * rows + 1, dtype=offsets.dtype)
    spread[0] = offsets[0]
    spread[1:] = np.repeat(offsets[1:], rows)
    valid = np.zeros((len(lists), rows), dtype=bool)
    valid[:, 0] = True
    validity = np.packbits(valid.reshape(-1), bitorder="little")  # Arrow's validity bitmap: LSB first, 1 = valid
    return pa.Array.from_buffers(  # from buffers: ListArray.from_arrays(mask=) would import pyarrow.compute (60 ms)
        lists.type,
        len(valid.reshape(-1)),
        [pa.py_buffer(validity), pa.py_buffer(spread)],
        children=[lists.values],
    )


def list_column(list_type: pa.DataType, values: pa.Array, step: int = 1) -> pa.Array:
    """``len(values) // step`` rows of ``step`` values each, over ``values`` (no copy): what Rerun's ``…columns()``
    and ``partition`` build for rows of equal length, without their per-row work (issue 38). ``list_type`` is the
    type Rerun gives the column (take it from a column its builder made)."""
    rows = len(values) // step
    offsets = pa.py_buffer(np.arange(0, rows * step + 1, step, dtype=np.int32))
    return pa.Array.from_buffers(list_type, rows, [None, offsets], children=[values])
