"""A ``--video`` recording (issue 32) in the real web viewer in headless Chromium: the camera's AV1 samples are
decoded by the browser and a frame shows (the scene's red block, 250/30/30, is on the page)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from camerabag import write_camera_bag
from conftest import cli

from . import viewers

pytestmark = [pytest.mark.e2e, pytest.mark.slow]
RED = (250, 30, 30)


def _red(img: np.ndarray) -> float:
    return viewers.color_fraction(img, RED, tol=40)


def test_a_video_recording_shows_its_camera_in_the_browser(chromium_browser, artifacts_dir: Path) -> None:
    write_camera_bag(artifacts_dir / "cam", 90)
    rrd = artifacts_dir / "video.rrd"
    result = cli("--bag", str(artifacts_dir / "cam"), "--save", str(rrd), "--video")
    assert result.returncode == 0, result.stderr
    shot = viewers.screenshot_web(
        rrd,
        artifacts_dir / "web_video.png",
        browser=chromium_browser,
        source="http",
        timeout=120,
        ready=lambda img: _red(img) > 0.002,  # the first frame shown, not the end of playback
        stable_polls=1,
        log_dir=artifacts_dir,
    )
    print(f"web --video: a camera frame after {shot.seconds:.1f} s, stages {shot.stages}")
    assert _red(viewers.load_png(shot.path)) > 0.002
