"""Sinks: the viewer binary the app uses, which sinks count as live, a port in use named."""

from __future__ import annotations

import os
import socket
from pathlib import Path

import pytest

from r2d2_viz.errors import SinkError
from r2d2_viz.viewer.sinks import SinkConfig, _check_port_free, viewer_executable


def test_the_viewer_is_the_binary_that_ships_with_this_python() -> None:
    """rerun_cli's own binary, not the console script in front of it (issue 36, finding 4: a signal to that
    script ended it and left the binary serving its port)."""
    import rerun_cli

    exe = viewer_executable()
    assert exe is not None and Path(exe) == Path(rerun_cli.__file__).parent / "rerun" and os.access(exe, os.X_OK)
    assert Path(exe).read_bytes()[:4] == b"\x7fELF"  # a program, not a script


def test_live_sinks() -> None:
    assert SinkConfig(spawn=True).live and SinkConfig(serve=True).live and SinkConfig(connect="x").live
    assert not SinkConfig(save=Path("x.rrd")).live and not SinkConfig(headless=True).live
    assert SinkConfig().bind == "127.0.0.1"  # safe by default


def test_a_port_in_use_is_named() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(SinkError, match=f"cannot listen on 127.0.0.1:{port} for the web viewer"):
            _check_port_free("127.0.0.1", port, "web viewer")


def test_a_recording_id_and_properties_given_to_the_sink(tmp_path: Path) -> None:
    """Issue 25: a fleet recording carries the id derived from its bag and what it says of the bag."""
    from rerun.chunk import RrdReader

    from r2d2_viz.viewer.sinks import SinkConfig, close_recording, open_recording

    rid = "6f1c2d3e-0000-4000-8000-00000000abcd"
    config = SinkConfig(recording_id=rid, properties=(("bag", "run_07"),))
    close_recording(open_recording(config, save_to=tmp_path / "a.rrd"))
    reader = RrdReader(tmp_path / "a.rrd")
    store = reader.recordings()[0]
    assert str(store.recording_id) == rid
    values = [
        chunk.to_record_batch().column("value").to_pylist()
        for chunk in reader.stream(store=store)
        if chunk.entity_path == "/__properties/bag"
    ]
    assert values == [[["run_07"]]]
