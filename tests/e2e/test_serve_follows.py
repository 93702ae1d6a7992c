"""``r2d2-viz --serve``'s page in headless Chromium: its viewer reads the recording from the page's own server (an
RRD that grows, under the run's token; no Rerun gRPC server) and follows it live, as it followed a gRPC stream.

Following, not playing from the start: the page is opened once the app has streamed at least ``HEAD_START_S`` of
robot time (the app paces to the wall clock, so waiting that long makes at least that much data), and the viewer's
first reported time is already past most of it; later ones go on growing.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from . import viewers
from .test_r2d2 import _served_url

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

HEAD_START_S = 6.0
TIMES = "window.r2d2.events.filter((e) => e.type === 'time_update').map((e) => e.time)"


def test_the_page_follows_the_growing_recording(chromium_browser, artifacts_dir: Path) -> None:
    web_port = viewers.free_port()
    exe = Path(sys.executable).parent / "r2d2-viz"
    log = artifacts_dir / "follow.log"
    with log.open("w") as sink:
        app = subprocess.Popen(
            [str(exe), "--serve", "--web-port", str(web_port), "--duration", "600"],
            stdout=sink,
            stderr=sink,
            start_new_session=True,
        )
    try:
        url = _served_url(log, app).replace("//localhost:", "//127.0.0.1:")
        time.sleep(HEAD_START_S)  # not a measurement: only so that the recording has this much robot time
        context = chromium_browser.new_context(viewport={"width": 1280, "height": 800}, color_scheme="dark")
        context.set_default_timeout(150_000)
        context.route("**/*", lambda route: route.continue_() if "127.0.0.1" in route.request.url else route.abort())
        page = context.new_page()
        page.goto(url)
        page.wait_for_function("window.r2d2 && window.r2d2.ready", timeout=150_000)
        page.wait_for_function(f"{TIMES}.length > 0", timeout=150_000)
        first = min(page.evaluate(TIMES))
        assert first >= HEAD_START_S / 2, f"the viewer started at {first} s: playing from the start, not following"
        page.wait_for_function(f"Math.max(...{TIMES}) > {first} + 2", timeout=150_000)  # and it goes on
        (artifacts_dir / "follow.png").write_bytes(page.screenshot())
        context.close()
    finally:
        viewers._stop_process_group(app)
