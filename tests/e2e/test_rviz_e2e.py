"""A converted RViz config in the native viewer: turtlebot3's model.rviz (an orbit looking nearly straight down)
with its background changed to a colour of our own, laid over the R2D2. Checked from the pixels: the 3D view's
background is that colour, and the grid is seen from above (straight lattice lines: whole pixel columns of grid),
which the tutorial's oblique view never shows."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from . import viewers

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

BACKGROUND = (20, 40, 90)
VIEW3D = (0.17, 0.10, 0.70, 0.95)


def _record(tmp: Path, name: str, *args: str) -> Path:
    out = tmp / f"{name}.rrd"
    exe = Path(sys.executable).parent / "r2d2-viz"
    subprocess.run([str(exe), "--save", str(out), "--duration", "0.5", *args], check=True, capture_output=True)
    return out


def _straight_grid_columns(img: np.ndarray) -> float:
    """The largest share of a pixel column of the 3D view's floor half that is not background: a grid line seen
    from above covers a whole column; lines seen at a slant cross each column in a few pixels."""
    view = img[viewers.region_slices(img.shape, (0.17, 0.55, 0.70, 0.95))].astype(int)
    background = np.median(view.reshape(-1, 3), axis=0)
    differs = np.abs(view - background).max(-1) > 20
    return float(differs.mean(axis=0).max())


def test_a_converted_config_sets_background_and_camera(x_display, artifacts_dir: Path) -> None:
    config = (REPO / "tests" / "data" / "rviz" / "turtlebot3_model.rviz").read_text()
    assert "Background Color: 48; 48; 48" in config
    ours = artifacts_dir / "model_blue.rviz"
    ours.write_text(config.replace("Background Color: 48; 48; 48", "Background Color: 20; 40; 90"))
    converted = _record(artifacts_dir, "converted", "--rviz", str(ours))
    tutorial = _record(artifacts_dir, "tutorial")
    shots = {}
    for name, rrd in (("converted", converted), ("tutorial", tutorial)):
        shot = viewers.screenshot_native(rrd, artifacts_dir / f"{name}.png", display=x_display.display)
        shots[name] = viewers.load_png(shot.path)
    colour, share = viewers.dominant_color(shots["converted"], VIEW3D)
    assert max(abs(c - b) for c, b in zip(colour, BACKGROUND, strict=True)) <= 3 and share > 0.5, (colour, share)
    tutorial_colour, _ = viewers.dominant_color(shots["tutorial"], VIEW3D)
    assert max(abs(c - 48) for c in tutorial_colour) <= 3  # the negative: the tutorial's own 48;48;48
    assert _straight_grid_columns(shots["converted"]) > 0.8  # seen from above: straight lattice lines
    assert _straight_grid_columns(shots["tutorial"]) < 0.6  # the tutorial's oblique view: lines converge
