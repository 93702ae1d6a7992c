"""The catalog layer (issue 25): a recording's id and marker read back; the server on loopback serving a folder;
what the fleet summary reads — the segment table's properties and time range, the joint plots, every /tf row
(several at one time) — checked against what was logged here by hand with Rerun's own API."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rerun as rr

from r2d2_viz.errors import UsageError
from r2d2_viz.viewer.catalog import (
    MARKER_PROPERTY,
    TOPICS_PROPERTY,
    catalog_server,
    read_fleet,
    recording_marker,
    server_url,
)

RID = "0b5e1a50-0000-4000-8000-000000000001"


def _write(path: Path) -> None:
    rec = rr.RecordingStream("r2d2_viz", recording_id=RID)
    rec.save(path)
    rec.send_property(MARKER_PROPERTY, rr.AnyValues(value='{"bag": "hand"}'))
    rec.send_property(TOPICS_PROPERTY, rr.AnyValues(value='{"/tf": ["tf2_msgs/msg/TFMessage", 2]}'))
    rec.log("/joints/limited", rr.SeriesLines(names=["a", "b"]), static=True)
    rec.log("/robot/visual/base/0", rr.CoordinateFrame("base"), static=True)
    for k in range(3):
        rec.set_time("time", timestamp=np.datetime64(1_700_000_000 + k, "s"))
        rec.log("/joints/limited", rr.Scalars([0.5 * k, -k]))
        for parent, child, x in (("odom", "base", float(k)), ("base", "arm", 9.0)):  # two rows at one time
            rec.log("/tf", rr.Transform3D(translation=[x, 0, 0], parent_frame=parent, child_frame=child))
    rec.flush()
    rec.disconnect()


def test_marker_server_and_what_the_summary_reads(tmp_path: Path) -> None:
    _write(tmp_path / "hand.rrd")
    assert recording_marker(tmp_path / "hand.rrd") == (RID, '{"bag": "hand"}')
    (tmp_path / "torn.bin").write_bytes(b"RRF2garbage")
    assert recording_marker(tmp_path / "torn.bin") is None
    with catalog_server(tmp_path, name="hand") as server:
        assert server_url(server).startswith("rerun+http://127.0.0.1:")
        data = read_fleet(server, "hand")
    segments = data.segments.to_pylist()
    assert len(segments) == 1 and segments[0]["segment"] == RID and segments[0]["bag"] == "hand"
    assert segments[0]["end_ns"] - segments[0]["start_ns"] == 2_000_000_000
    times, values, names = data.joints[RID]
    assert names == ["a", "b"] and np.allclose(values, [[0, 0], [0.5, -1], [1, -2]])
    assert np.array_equal(np.diff(times), [1_000_000_000] * 2)
    edges = {(p, c): xyz[:, 0].tolist() for p, c, _, xyz, _ in data.edges[RID]}
    assert edges == {("odom", "base"): [0.0, 1.0, 2.0], ("base", "arm"): [9.0, 9.0, 9.0]}
    assert data.links[RID] == {"base"}


def test_a_folder_that_is_not_one_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="must be a directory"), catalog_server(tmp_path / "nope", name="x"):
        pass
