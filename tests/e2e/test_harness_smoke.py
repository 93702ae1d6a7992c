"""Prove the viewer harness: what it sees in the real web and native Rerun viewers is what's there.

A toy recording (white box, blue box, a scalar series) with a default blueprint giving the 3D view
a 48;48;48 background is opened in the native viewer; the pixel checks must pass for it and must FAIL
for two negatives: the same recording without the boxes, and the boxes with the viewer's own
default blueprint (so the background is not 48;48;48). The web viewer's harness is proven by
tests/e2e/test_r2d2.py's web cases (a positive and a negative, the same helpers).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import rerun as rr
import rerun.blueprint as rrb

from . import viewers

BACKGROUND = (48, 48, 48)
WHITE = (255, 255, 255)
BLUE = (0, 0, 200)

# Where the 3D view sits in both viewers for the toy blueprint (Horizontal[3D, time series] between
# the default side panels), as fractions of the screenshot: web 1280x800 → x 200..590, y 64..600;
# native (2x) 2560x1600 → x 434..1180, y 130..1200. This region is inside the 3D view in both.
VIEW3D: viewers.Region = (0.17, 0.10, 0.45, 0.74)


def make_toy_rrd(path: Path, *, boxes: bool = True, custom_blueprint: bool = True) -> Path:
    rec = rr.RecordingStream("rerun_example_e2e")
    if custom_blueprint:
        blueprint = rrb.Blueprint(
            rrb.Horizontal(
                rrb.Spatial3DView(
                    origin="/",
                    background=[*BACKGROUND],
                    line_grid=rrb.LineGrid3D(
                        visible=True,
                        spacing=1.0,
                        plane=rr.components.Plane3D.XY,
                        color=[160, 160, 164, 128],
                    ),
                    # Far enough away that the background, not the big box, fills most of the view.
                    eye_controls=rrb.EyeControls3D(position=[7, -9, 5], look_target=[1, 0, 0.5], eye_up=[0, 0, 1]),
                ),
                rrb.TimeSeriesView(origin="/joints"),
            )
        )
        rec.save(path, default_blueprint=blueprint)
    else:
        rec.save(path)
    if boxes:
        rec.log(
            "world/big",
            rr.Boxes3D(centers=[[0, 0, 1]], half_sizes=[[1, 1, 1]], colors=[[255, 255, 255]], fill_mode="solid"),
            static=True,
        )
        rec.log(
            "world/small",
            rr.Boxes3D(centers=[[2.5, 0, 0.3]], half_sizes=[[0.3, 0.3, 0.3]], colors=[[0, 0, 255]], fill_mode="solid"),
            static=True,
        )
    for i in range(20):  # short timeline: SwiftShader plays only a few steps per second
        rec.set_time("step", sequence=i)
        rec.log("joints/a", rr.Scalars(math.sin(i / 3)))
    rec.flush()
    return path


def toy_scene_problems(img: np.ndarray) -> list[str]:
    """Empty when the screenshot shows the toy scene as intended; else what is wrong."""
    problems: list[str] = []
    bg_colour, bg_share = viewers.dominant_color(img, VIEW3D)
    bg = viewers.color_fraction(img, BACKGROUND, tol=2, region=VIEW3D)
    if bg < 0.5 or max(abs(c - b) for c, b in zip(bg_colour, BACKGROUND, strict=True)) > 2:
        problems.append(f"3D background: dominant {bg_colour} ({bg_share:.1%}), 48;48;48 covers {bg:.1%}")
    white = viewers.color_fraction(img, WHITE, tol=30, region=VIEW3D)
    if white < 0.002:
        problems.append(f"white pixels in 3D view: {white:.3%}")
    blue = viewers.color_fraction(img, BLUE, tol=70, region=VIEW3D)
    if blue < 0.001 or viewers.color_bbox(img, BLUE, tol=70, region=VIEW3D) is None:
        problems.append(f"blue pixels in 3D view: {blue:.3%}")
    return problems


Shooter = Callable[[Path, Path], Path]


def shooter(viewer: str, request: pytest.FixtureRequest, artifacts_dir: Path) -> Shooter:
    """shoot(rrd, png) -> png, through ``viewer``."""
    if viewer == "web":
        browser = request.getfixturevalue("chromium_browser")

        def web(rrd: Path, png: Path) -> Path:
            shot = viewers.screenshot_web(rrd, png, browser=browser, source="http", timeout=90, log_dir=artifacts_dir)
            print(f"web {png.name}: {shot.seconds:.1f}s stages={shot.stages} renderer={shot.renderer}")
            return shot.path

        return web
    display = request.getfixturevalue("x_display")

    def native(rrd: Path, png: Path) -> Path:
        shot = viewers.screenshot_native(rrd, png, display=display.display, timeout=90)
        print(f"native {png.name}: {shot.seconds:.1f}s adapter={shot.adapter}")
        return shot.path

    return native


CASES = {
    "toy": {"boxes": True, "custom_blueprint": True},
    "no_boxes": {"boxes": False, "custom_blueprint": True},
    "default_blueprint": {"boxes": True, "custom_blueprint": False},
}


@pytest.mark.e2e
@pytest.mark.slow
# in the native viewer only: the web viewer's positive and negative cases are tests/e2e/test_r2d2.py's (the robot on
# our layout, then no robot), through the same screenshot_web and pixel helpers, each page load costing 12-30 s of
# SwiftShader (the toy's was 16 s of a loaded run)
@pytest.mark.parametrize(("viewer", "case"), [("native", case) for case in CASES])
def test_viewer_shows_toy_scene(
    viewer: str, case: str, request: pytest.FixtureRequest, tmp_path: Path, artifacts_dir: Path
) -> None:
    shoot = shooter(viewer, request, artifacts_dir)
    rrd = make_toy_rrd(tmp_path / f"{case}.rrd", **CASES[case])
    t0 = time.monotonic()
    png = shoot(rrd, artifacts_dir / f"{case}.png")
    elapsed = time.monotonic() - t0
    img = viewers.load_png(png)
    problems = toy_scene_problems(img)
    print(f"{case}: {img.shape[1]}x{img.shape[0]} in {elapsed:.1f}s; problems={problems}")
    if case == "toy":
        assert problems == [], f"{png}: {problems}"
    else:
        assert problems, f"{png}: negative case {case!r} passed the positive check"
        if case == "no_boxes":
            assert all("background" not in p for p in problems), problems
            assert any("white" in p for p in problems) and any("blue" in p for p in problems), problems
        else:
            assert any("background" in p for p in problems), problems


# ---- pixel helpers (fast, no viewer) ----


def test_pixel_helpers_on_synthetic_image(tmp_path: Path) -> None:
    from PIL import Image

    img = np.zeros((100, 200, 3), dtype=np.uint8)
    img[:] = BACKGROUND
    img[10:20, 30:50] = (250, 251, 252)  # white patch
    img[60:70, 150:160] = (0, 0, 210)  # blue patch
    path = tmp_path / "synthetic.png"
    Image.fromarray(img).save(path)
    loaded = viewers.load_png(path)
    assert loaded.shape == (100, 200, 3) and loaded.dtype == np.uint8
    assert viewers.color_fraction(loaded, WHITE, tol=8) == pytest.approx(200 / 20000)
    assert viewers.color_fraction(loaded, WHITE, tol=2) == 0.0
    assert viewers.color_fraction(loaded, WHITE, tol=8, region=(0.5, 0.5, 1.0, 1.0)) == 0.0
    assert viewers.color_fraction(loaded, BLUE, tol=20, region=(0.5, 0.5, 1.0, 1.0)) == pytest.approx(100 / 5000)
    assert viewers.color_bbox(loaded, WHITE, tol=8) == (30, 10, 50, 20)
    assert viewers.color_bbox(loaded, BLUE, tol=20, region=(0.5, 0.5, 1.0, 1.0)) == (150, 60, 160, 70)
    assert viewers.color_bbox(loaded, (255, 0, 0), tol=8) is None
    colour, share = viewers.dominant_color(loaded)
    assert colour == BACKGROUND and share == pytest.approx(1 - 300 / 20000)
    assert viewers.bbox_to_region((30, 10, 50, 20), loaded.shape) == (0.15, 0.1, 0.25, 0.2)
    with pytest.raises(ValueError):
        viewers.color_fraction(loaded, WHITE, region=(0.5, 0.0, 0.4, 1.0))
