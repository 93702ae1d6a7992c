"""The flags every run reads, read once: ``--shared-frames`` by hand, and a run's configuration from a parsed
command line (what the caller sets wins over the flags)."""

from __future__ import annotations

from pathlib import Path

import pytest

from r2d2_viz.cli.parser import build_parser
from r2d2_viz.cli.run_args import run_config, shared_frames
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
