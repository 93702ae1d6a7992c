"""Arrow columns built once and sliced: the same rows as building them the slow way, read back from a file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from rrd import read_recording

from r2d2_viz.viewer.columns import (
    encoded,
    f32,
    first_of_every,
    flat_array,
    float32_array,
    list_column,
    packed_rgba,
    send,
    tiled,
    time_array,
)


def test_tiled_is_texts_times_n() -> None:
    texts = ["odom", "base link", "ünïcode/with/slashes", ""]
    assert tiled(texts, 5).to_pylist() == texts * 5
    assert tiled(texts, 0).to_pylist() == []


def test_first_of_every_puts_each_list_on_the_first_row_and_nulls_elsewhere() -> None:
    lists = pa.array([[1.0, 2.0], [3.0], []], type=pa.list_(pa.float64()))
    spread = first_of_every(lists, 3)
    assert spread.to_pylist() == [[1.0, 2.0], None, None, [3.0], None, None, [], None, None]
    assert first_of_every(lists, 1) is lists


def test_sending_a_slice_sends_exactly_those_rows(tmp_path: Path) -> None:
    out = tmp_path / "c.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    n = 10
    columns = encoded(rr.Scalars.columns(scalars=np.arange(n, dtype=np.float64) * 1.5))
    times = time_array(np.arange(n, dtype=np.int64) * 1000, "duration")
    send(rec, "/whole", "time", times, columns)
    send(rec, "/part", "time", times, columns, 3, 4)  # rows 3 … 6
    stamps = time_array(np.array([1_700_000_000_000_000_000], dtype=np.int64), "timestamp")
    send(rec, "/stamped", "time2", stamps, encoded(rr.Scalars.columns(scalars=[7.0])))
    rec.flush()
    rec.disconnect()
    recording = read_recording(out)
    assert [v[0] for v in recording["/whole"].temporal["Scalars:scalars"]] == [k * 1.5 for k in range(n)]
    assert recording["/part"].times == [3000, 4000, 5000, 6000]
    assert [v[0] for v in recording["/part"].temporal["Scalars:scalars"]] == [4.5, 6.0, 7.5, 9.0]
    assert times.type == pa.duration("ns") and stamps.type == pa.timestamp("ns")


def test_f32_turns_doubles_beyond_float32_into_inf_silently() -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = f32(np.array([1e300, -1e300, 0.5, np.nan]))
    assert out.dtype == np.float32
    assert out[0] == np.inf and out[1] == -np.inf and out[2] == 0.5 and np.isnan(out[3])


def test_list_column_is_rows_of_step_values_over_the_same_buffer() -> None:
    """Issue 38: ``list_column`` is what ``partition`` into rows of equal length makes, without a copy."""
    values = pa.array(np.arange(12, dtype=np.float64))
    (expected,) = [c.as_arrow_array() for c in rr.Scalars.columns(scalars=np.arange(12.0)).partition([3, 3, 3, 3])]
    got = list_column(expected.type, values, 3)
    assert got.equals(expected)
    assert got.to_pylist() == [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0], [6.0, 7.0, 8.0], [9.0, 10.0, 11.0]]
    assert got.values.buffers()[1].address == values.buffers()[1].address  # no copy
    assert list_column(expected.type, values).to_pylist() == [[float(k)] for k in range(12)]


@pytest.mark.parametrize(("clock", "kind"), [("duration", "timedelta64[ns]"), ("timestamp", "datetime64[ns]")])
def test_time_array_is_what_pyarrow_makes_of_numpy_times_and_owns_its_values(clock: str, kind: str) -> None:
    """Built from buffers (see ``time_array``): the same Arrow type and values as pyarrow's own conversion of numpy's
    duration or datetime array, and a copy (the caller's array may be reused)."""
    times = np.array([0, 1, 1_700_000_000_123_456_789, -5], dtype=np.int64)
    got = time_array(times, clock)  # type: ignore[arg-type]
    assert got.equals(pa.array(times.astype(kind)))
    times[0] = 42
    assert got[0].value == 0


def test_flat_arrays_and_packed_rgba_are_what_pyarrow_and_rerun_make() -> None:
    values = np.array([[1.5, np.nan, -np.inf], [3.0, 4.0, 1e-3]], dtype=np.float32)
    got, expected_floats = float32_array(values), pa.array(values.reshape(-1))
    assert got.type == expected_floats.type and got.null_count == expected_floats.null_count == 0  # NaN: a value
    assert (got.to_numpy().view(np.uint32) == expected_floats.to_numpy().view(np.uint32)).all()  # bit for bit
    doubles = np.array([[0.1, np.nan], [-2.5, 1e300]])
    assert flat_array(doubles).type == pa.float64()
    assert (
        flat_array(doubles).to_numpy().view(np.uint64) == pa.array(doubles.reshape(-1)).to_numpy().view(np.uint64)
    ).all()
    expected = rr.components.ColorBatch(np.array([[255, 0, 255]] * 2, dtype=np.uint8)).as_arrow_array()
    assert packed_rgba((255, 0, 255), 2).equals(expected)
