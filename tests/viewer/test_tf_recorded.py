"""Recorded transforms into a recording, read back with Rerun's reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
from rrd import read_recording, tf_by_child

from r2d2_viz.sources.base import TfRecords
from r2d2_viz.viewer.tf_recorded import RecordedTf, TfFeed

T0 = 1_700_000_000_000_000_000


def _records(times, parents, children, translations, *, static: bool = False) -> TfRecords:
    n = len(times)
    return TfRecords(
        np.array(times, dtype=np.int64),
        tuple(parents),
        tuple(children),
        np.array(translations, dtype=np.float64).reshape(n, 3),
        np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
        static,
    )


def test_static_and_moving_transforms_axes_and_arrows(tmp_path: Path) -> None:
    out = tmp_path / "tf.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    recorded = RecordedTf(rec, clock="timestamp", skip={("base", "arm")})
    recorded.log(_records([T0, T0 + 5], ["base", "base"], ["laser", "laser"], [[1, 0, 0], [2, 0, 0]], static=True))
    feed = TfFeed(recorded)
    assert feed.next_time_ns is None
    feed.push(None)  # a window without /tf
    feed.push(
        _records(
            [T0 + 30, T0 + 10, T0 + 20, T0 + 20],  # out of order: the feed sorts by time
            ["map", "map", "map", "base"],
            ["base", "base", "base", "arm"],  # base → arm is the URDF's: skipped
            [[3, 0, 0], [1, 0, 0], [2, 0, 0], [9, 9, 9]],
        ),
    )
    assert feed.next_time_ns == T0 + 10
    feed.until(T0 + 20)
    assert recorded.rows == 2 + 2  # two static rows, then base at 10 and 20 (arm skipped)
    assert feed.next_time_ns == T0 + 30 and feed.logged == 3  # base at 10, 20 and the (skipped) arm at 20
    feed.push(_records([T0 + 40], ["map"], ["base"], [[4, 0, 0]]))  # the next window's
    feed.until(T0 + 35)
    assert feed.next_time_ns == T0 + 40
    feed.until(None)
    assert feed.next_time_ns is None and feed.logged == 5
    rec.flush()
    rec.disconnect()
    recording = read_recording(out)
    laser = recording["/tf_static/laser"].static
    assert laser["Transform3D:parent_frame"][-1] == ["base"]
    assert np.allclose(laser["Transform3D:translation"][-1][0], [2, 0, 0])  # the last one wins, as in tf2
    base = tf_by_child(recording)["base"]
    assert base.times == [T0 + 10, T0 + 20, T0 + 30, T0 + 40]
    assert [t[0][0] for t in base.temporal["Transform3D:translation"]] == [1, 2, 3, 4]
    assert "arm" not in tf_by_child(recording)
    assert {"/tf_axes/map", "/tf_axes/base", "/tf_axes/laser"} <= set(recording)
    arrow = recording["/tf_arrows/base"]
    assert arrow.static["CoordinateFrame:frame"][-1] == ["map"]
    assert [o[0][0] for o in arrow.temporal["Arrows3D:origins"]] == [1, 2, 3, 4]
    assert [v[0][0] for v in arrow.temporal["Arrows3D:vectors"]] == [-1, -2, -3, -4]
