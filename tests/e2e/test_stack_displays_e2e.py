"""nav2's and vision_msgs' displays in the real native viewer (Xvfb, lavapipe): the stack bag (:mod:`stackbags`)
with its .rviz config (ParticleCloud as green 3D arrows, Detection3DArray as half-transparent edges, the camera's
Image in a 2D view), paused at the messages' time. Checked from the pixels: the red voxels, the green particle
ring, the car's orange box edges in the 3D view; the person's blue outline in the image's 2D view; and no view
reports an error."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from stackbags import T0, stack_recordings

from . import viewers

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

S = 1_000_000_000
WINDOW = (1600, 1000)  # the PNG is 2x


VIEW3D: viewers.Region = (0.14, 0.08, 0.69, 0.95)  # inside the 3D view (left) of the RViz-like layout
IMAGE_VIEW: viewers.Region = (0.72, 0.08, 0.99, 0.62)  # inside the image's 2D view (right, above the warnings)


def colour_pixels(img: np.ndarray) -> dict[str, int]:
    """Pixels of each display's colour class in its view (shading darkens the solids, so classes, not exact
    values; the image is a green ramp, so the particles' green is looked for in the 3D view only)."""
    rgb = img[..., :3].astype(np.int16)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    scene = np.zeros(img.shape[:2], dtype=bool)
    scene[viewers.region_slices(img.shape, VIEW3D)] = True
    image = np.zeros(img.shape[:2], dtype=bool)
    image[viewers.region_slices(img.shape, IMAGE_VIEW)] = True
    return {
        "voxels": int((scene & (r > 120) & (g < 40) & (b < 40)).sum()),  # red
        "particles": int((scene & (g > 100) & (r < 40) & (b < 40)).sum()),  # green (0, 180, 0)
        "car": int((scene & (r > 150) & (g > 80) & (g < 140) & (b < 40)).sum()),  # orange (255, 165, 0), alpha 0.5
        "person": int((image & (b > 150) & (r < 40) & (g < 40)).sum()),  # blue (0, 0, 255) outline on the image
    }


def test_native_viewer(tmp_path_factory: pytest.TempPathFactory, x_display, artifacts_dir: Path) -> None:
    rrd = stack_recordings(tmp_path_factory)["rviz"]
    png = artifacts_dir / "native_stack.png"
    with viewers.native_viewer(x_display.display, WINDOW, artifacts_dir / "native_stack.log") as client:
        client.open(str(rrd))
        deadline = time.monotonic() + 60
        while not any(t.name == "time" for r in client.get_state().recordings for t in r.timelines):
            assert time.monotonic() < deadline, "no 'time' timeline"
            time.sleep(0.5)
        client.set_time("time", timestamp=np.datetime64(T0 + S // 5, "ns"), play_state="paused")
        img = viewers.still_screenshot(client, png)
        reports = [r.summary for v in client.get_state().views for r in v.reports if r.severity == "error"]
    found = colour_pixels(img)
    print(f"{png}: {found}")
    assert reports == [], reports[:5]
    minimum = {"voxels": 1000, "particles": 800, "car": 1500, "person": 200}  # a quarter of what a run draws
    assert all(found[k] >= n for k, n in minimum.items()), found
