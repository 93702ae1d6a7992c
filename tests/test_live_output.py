"""Where a live run is written (``r2d2_viz.live_output``): a failed run leaves nothing half-written, and a file sink
stuck on a full disk is one line naming the file (issue 44, item 14; the whole CLI on a full tmpfs:
tests/viewer/files/test_whole.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from r2d2_viz.errors import R2d2VizError
from r2d2_viz.live_output import LiveOutput
from r2d2_viz.viewer.files.whole import WriterStuckError
from r2d2_viz.viewer.sinks import SinkConfig


def test_a_save_is_written_beside_its_target_and_an_abort_removes_it(tmp_path: Path) -> None:
    target = tmp_path / "out.rrd"
    target.write_bytes(b"an older recording")
    output = LiveOutput(SinkConfig(save=target, headless=True))
    assert output.tmp is not None and output.tmp.parent == tmp_path and output.tmp.name.startswith(".out.rrd.")
    output.tmp.write_bytes(b"half a recording")
    output.abort(KeyboardInterrupt())
    assert not output.tmp.exists() and target.read_bytes() == b"an older recording"


def test_a_stuck_writer_is_one_line_naming_the_file(tmp_path: Path) -> None:
    target = tmp_path / "out.rrd"
    output = LiveOutput(SinkConfig(save=target, headless=True))
    assert output.tmp is not None
    output.tmp.write_bytes(b"half a recording")
    with pytest.raises(R2d2VizError) as caught:
        output.abort(WriterStuckError("stalled"))
    assert str(caught.value).startswith(f"{target}: not saved: ") and "\n" not in str(caught.value)
    assert not output.tmp.exists() and not target.exists()


def test_an_mcap_save_records_a_bag_and_sends_the_viewer_nothing_to_a_file(tmp_path: Path) -> None:
    output = LiveOutput(SinkConfig(save=tmp_path / "out.mcap", headless=True))
    assert output.bag_path == tmp_path / "out.mcap" and output.rrd is None and output.tmp is None
    assert output.sink.save is None
