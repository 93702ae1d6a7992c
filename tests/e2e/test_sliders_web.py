"""``--motion sliders --serve``: the sliders' panel sits beside Rerun's web viewer, not over it. The viewer's widget
sets its element's width to 100% (inline), so beside the panel the viewer ran on under it: the panel covered the
plots' legends and the time panel's time field (issue 44). Measured in headless Chromium, at two window sizes: the
viewer ends where the panel begins, and the viewer's canvas too."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import REPO

from e2e import viewers

pytestmark = pytest.mark.e2e


def test_the_sliders_panel_covers_no_part_of_the_viewer(chromium_browser, artifacts_dir: Path) -> None:
    web_port = viewers.free_port()
    exe = Path(sys.executable).parent / "r2d2-viz"
    log = artifacts_dir / "sliders_web.log"
    arm = REPO / "examples" / "arm6.urdf"
    command = [str(exe), "--urdf", str(arm), "--motion", "sliders", "--serve", "--web-port", str(web_port)]
    with log.open("w") as sink:
        app = subprocess.Popen([*command, "--duration", "120"], stdout=sink, stderr=sink, start_new_session=True)
    try:
        deadline, found = time.monotonic() + 60, None
        while found is None and time.monotonic() < deadline and app.poll() is None:
            found = re.search(r"(http://localhost:\d+/[^/\s]+/)", log.read_text())
            time.sleep(0.2)
        assert found is not None, log.read_text()
        url = found.group(1).replace("//localhost:", "//127.0.0.1:")
        for width, height in ((1280, 800), (900, 600)):
            context = chromium_browser.new_context(viewport={"width": width, "height": height}, color_scheme="dark")
            context.route("**/*", lambda r: r.continue_() if "127.0.0.1" in r.request.url else r.abort())
            page = context.new_page()
            page.goto(url)
            page.wait_for_function(
                "document.querySelector('#sliders .joint') && document.querySelector('#viewer canvas')"
            )
            rects = page.evaluate(
                """() => Object.fromEntries(["#viewer", "#viewer canvas", "#sliders"].map((s) => {
                     const r = document.querySelector(s).getBoundingClientRect();
                     return [s, [r.left, r.right, r.width]];
                   }))"""
            )
            page.screenshot(path=str(artifacts_dir / f"sliders_web_{width}.png"))
            context.close()
            panel_left = rects["#sliders"][0]
            assert rects["#sliders"][1] == width and rects["#sliders"][2] == 300, rects  # the panel, on the right
            assert rects["#viewer"][1] <= panel_left and rects["#viewer canvas"][1] <= panel_left, rects
            assert rects["#viewer"][2] == width - 300, rects  # and the viewer has all the rest
    finally:
        viewers._stop_process_group(app)
