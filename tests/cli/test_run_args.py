"""The flags every run reads, read once: ``--shared-frames`` by hand, and a run's configuration from a parsed
command line (what the caller sets wins over the flags)."""

from __future__ import annotations

from pathlib import Path

import pytest

from r2d2_viz.cli.parser import build_parser
from r2d2_viz.cli.run_args import run_config, shared_frames, sink_config
from r2d2_viz.errors import UsageError


def test_shared_frames_are_the_names_between_commas() -> None:
    assert shared_frames(None) is None
    assert shared_frames(" map, world ,") == ("map", "world")
    with pytest.raises(UsageError, match="expected frame names separated by commas"):
        shared_frames(" , ")


def test_a_run_config_reads_the_flags_and_the_caller_decides_the_rest(tmp_path: Path) -> None:
    bag = tmp_path / "b.mcap"
    args = build_parser().parse_args(
        [
            "--bag",
            str(bag),
            "--time",
            "header",
            "--shared-frames",
            "map",
            "--plot",
            "/odom.x",
            "--mass",
            "--topics",
            "/a",
        ]
    )
    config = run_config(args, bag=bag, realtime=True)
    assert config.bag == bag and config.realtime
    assert config.time == "header" and config.shared_frames == ("map",)
    assert config.plots == (("/odom.x",),) and config.show == frozenset({"mass"}) and config.topics == ("/a",)


@pytest.mark.parametrize(("display", "spawn", "serve"), [("", False, True), (":99", True, False)])
def test_with_no_sink_flag_the_native_viewer_or_where_no_window_opens_the_web_one(
    monkeypatch: pytest.MonkeyPatch, display: str, spawn: bool, serve: bool
) -> None:
    """RViz opens a window; where none can open (no DISPLAY on Linux) the served page is the viewer."""
    monkeypatch.setenv("DISPLAY", display)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    args = build_parser().parse_args(["--web-port", "9100", "--port", "9877"])
    sink = sink_config(args, implied=True, page=True)
    assert (sink.spawn, sink.serve, sink.port, sink.web_port, sink.page) == (spawn, serve, 9877, 9100, True)
    told = sink_config(build_parser().parse_args(["--save", "x.rrd"]), implied=False)
    assert (told.spawn, told.serve, told.save) == (False, False, Path("x.rrd"))
