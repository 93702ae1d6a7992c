"""A missing mesh is a row of the Warnings view on the served page (issue 44, item 17), end to end: ``r2d2-viz
--serve`` of the tutorial R2D2 with one mesh that is not there, the page opened in headless Debian Chromium.

The page is a canvas: the row is seen from its pixels. The run says exactly one warning (the R2D2's joint limits are
widened so the tutorial's motion stays inside them: no out-of-limits row), and the Warnings view's rows show their
level, ``WARN``, in Rerun's warning orange — so orange text in that view is the missing mesh's row. Before the fix
the row was static, the view showed none (issue 44's screenshot: an empty table under its header). The view is then
maximised (its header's button) and saved as ``warnings_view.png`` for a person to read the row."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from . import viewers
from .test_r2d2 import WEB_VIEWPORT, _served_url

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

WARN_ORANGE = (255, 122, 12)
"""The ``WARN`` level's text colour in Rerun 0.41's dark theme (measured on a screenshot of the page)."""
WARNINGS_VIEW = (0.73, 0.87, 1.0, 0.97)
"""The Warnings view's rows on our layout at 1280 x 800: below the two plots, right of the 3D view."""
MAXIMISE = (1262, 669)
"""The Warnings view's maximise button (its header's right end) on that layout, in pixels."""
MISSING = "mesh file 'meshes/gone.stl' not found"


def _urdf(folder: Path) -> Path:
    from r2d2_viz.robot.model import default_urdf_path

    text = default_urdf_path().read_text()
    gone = '<visual><geometry><mesh filename="meshes/gone.stl"/></geometry></visual></link><link name="leg1">'
    text = text.replace('</link><link name="leg1">', gone, 1)
    text = text.replace('<limit upper="0" lower="-.5"', '<limit upper="1" lower="-1"')  # the motion stays inside
    path = folder / "missing_mesh.urdf"
    path.write_text(text)
    return path


def _warn_pixels(img: np.ndarray) -> int:
    rows, cols = viewers.region_slices(img.shape, WARNINGS_VIEW)
    return int(viewers.color_mask(img[rows, cols], WARN_ORANGE, tol=30).sum())


def test_a_missing_mesh_is_a_row_of_the_served_pages_warnings_view(chromium_browser, artifacts_dir: Path) -> None:
    exe = Path(sys.executable).parent / "r2d2-viz"
    log = artifacts_dir / "app.log"
    command = [str(exe), "--serve", "--web-port", str(viewers.free_port()), "--urdf", str(_urdf(artifacts_dir)),
               "--duration", "300"]  # fmt: skip
    with log.open("w") as sink:
        app = subprocess.Popen(command, stdout=sink, stderr=sink, start_new_session=True)
    try:
        url = _served_url(log, app).replace("//localhost:", "//127.0.0.1:")
        context = chromium_browser.new_context(
            viewport={"width": WEB_VIEWPORT[0], "height": WEB_VIEWPORT[1]}, color_scheme="dark"
        )
        context.set_default_timeout(150_000)
        context.route("**/*", lambda route: route.continue_() if "127.0.0.1" in route.request.url else route.abort())
        page = context.new_page()
        page.goto(url)
        page.wait_for_function("window.r2d2 && window.r2d2.ready", timeout=150_000)
        deadline = time.monotonic() + 150  # bounded: SwiftShader on a busy 2-core machine
        while _warn_pixels(viewers._decode_png(png := page.screenshot())) < 20:
            if time.monotonic() > deadline:
                (artifacts_dir / "page.png").write_bytes(png)
                raise AssertionError(f"{artifacts_dir / 'page.png'}: no WARN row in the Warnings view")
            time.sleep(2.0)
        (artifacts_dir / "page.png").write_bytes(png)
        page.mouse.move(*MAXIMISE)  # egui sees a press and a release in separate frames
        time.sleep(0.5)
        page.mouse.down()
        time.sleep(0.3)
        page.mouse.up()
        time.sleep(2.0)
        (artifacts_dir / "warnings_view.png").write_bytes(png := page.screenshot())
        maximised = viewers._decode_png(png)
        assert int(viewers.color_mask(maximised, WARN_ORANGE, tol=30)[100:].sum()) >= 20  # below the top bar
        context.close()
    finally:
        viewers._stop_process_group(app)
    said = [line for line in log.read_text().splitlines() if line.startswith("warning:")]
    assert len(said) == 1 and MISSING in said[0], said  # the one row the view shows: the missing mesh
    assert not re.search(r"left its URDF limits", log.read_text())
