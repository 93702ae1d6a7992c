"""``--motion sliders --spawn``: the native viewer opens and the sliders' page is served beside it, its URL printed
(the issue: "where the native viewer is used, the slider page is served alongside"); a slider moved there (POSTed
as the page does) is in the recording."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

from rrd import read_recording

from e2e import viewers


def test_sliders_beside_the_native_viewer(x_display: viewers.XDisplay, artifacts_dir: Path) -> None:
    port, web_port = viewers.free_port(), viewers.free_port()
    exe = Path(sys.executable).parent / "r2d2-viz"
    out = artifacts_dir / "sliders.rrd"
    log = artifacts_dir / "sliders.log"
    with log.open("w") as sink:  # not a pipe: the detached viewer inherits it and would keep it open
        app = subprocess.Popen(
            [
                str(exe),
                "--motion",
                "sliders",
                "--spawn",
                "--port",
                str(port),
                "--web-port",
                str(web_port),
                "--save",
                str(out),
                "--duration",
                "8",
            ],
            env=viewers.native_render_env(x_display.display),
            stdout=sink,
            stderr=sink,
        )
    viewer_pids: list[int] = []
    try:
        deadline, found = time.monotonic() + 60, None
        while found is None and time.monotonic() < deadline and app.poll() is None:
            found = re.search(r"the page with the sliders: open (http://localhost:\d+/[^/\s]+/)", log.read_text())
            time.sleep(0.2)
        assert found is not None, log.read_text()
        page = found.group(1)
        deadline, joints = time.monotonic() + 60, None
        while joints is None and time.monotonic() < deadline:  # attached just after the line is printed
            with urllib.request.urlopen(page, timeout=30) as answer:
                joints = re.search(r'"joints": \[', answer.read().decode())
            time.sleep(0.1)
        event = json.dumps({"tool": "Joints", "joint": "tilt", "position": -0.3}).encode()
        with urllib.request.urlopen(urllib.request.Request(page + "event", data=event), timeout=30) as answer:
            assert json.loads(answer.read()) == {"line": "tilt = -0.3"}
        assert app.wait(timeout=120) == 0, log.read_text()
    finally:
        if app.poll() is None:
            app.terminate()
            app.wait(timeout=30)
        found_pids = subprocess.run(["pgrep", "-f", f"rerun.*--port={port}"], capture_output=True, text=True)
        viewer_pids = [int(p) for p in found_pids.stdout.split()]
        for pid in viewer_pids:  # the viewer this test spawned, by its own pid
            try:
                os.kill(pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
    plot = read_recording(out)["/joints/limited"]
    names = plot.static["SeriesLines:names"][-1]
    tilt = [row[names.index("tilt")] for row in plot.temporal["Scalars:scalars"]]
    assert tilt[0] == 0.0 and tilt[-1] == -0.3
