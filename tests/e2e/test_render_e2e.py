"""``--render`` through the real CLI and Rerun's real headless viewer (issue 45), on a 60 s bag whose robot holds
still for 20 s, moves for 20 s and holds still again (tests/renderbags.py), rendered once at 1 fps for the module.

The likeness to the native viewer: ``rerun FILE --screenshot-to`` under Xvfb (tests/e2e/viewers.py) screenshots the
whole viewer, with the recording's own layout, a moment after it opened the recording — at its start, playing, so
within the first 20 s, where the robot has not moved yet. Its 3D view is cut out (the rectangle of the view's
#303030 background) and compared with a rendered frame from the same still stretch, both scaled to 72 pixels high
(the video's frame centre-cut to the view's aspect: Rerun's 3D camera keeps its vertical field of view). Bounds,
from one run on this machine (lavapipe): the same pose gave a mean absolute difference of 2.7 levels and a
correlation of 0.97; the moved robot (t = 59 s) 8.3 and 0.13. So: ≤ 5 levels and ≥ 0.9, and the moved frame must
fail them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import av
import numpy as np
import pytest
from conftest import cli
from PIL import Image
from renderbags import DURATION_S, MOVING_S, write_render_bag

from . import viewers
from .conftest import unavailable

pytestmark = [pytest.mark.e2e, pytest.mark.slow]
FPS = 1
SIZE = (640, 360)
STILL_LEVELS = 0.1
"""Mean absolute difference (levels, 0-255) between two frames of a robot holding still: measured 0.00."""
MOVING_LEVELS = 0.3
"""…and between two frames 1 s apart while it moves: measured 0.70-0.78 at 640x360 (the robot covers ~3 % of it)."""


@dataclass(frozen=True)
class Rendered:
    bag: Path
    video: Path
    stderr: str
    frames: list[np.ndarray]
    codec: str
    size: tuple[int, int]


@pytest.fixture(scope="module")
def rendered(tmp_path_factory: pytest.TempPathFactory) -> Rendered:
    missing = [r for r in viewers.missing_native_prerequisites() if "Xvfb" not in r and "libX11" not in r]
    if missing:
        unavailable("; ".join(missing))  # a skip; under CI a failure
    folder = tmp_path_factory.mktemp("render")
    bag = write_render_bag(folder / "moving")
    video = folder / "moving.mp4"
    size = f"{SIZE[0]}x{SIZE[1]}"
    result = cli("--bag", str(bag), "--render", str(video), "--fps", str(FPS), "--size", size, timeout=600)
    assert result.returncode == 0, result.stderr
    with av.open(str(video)) as container:
        stream = container.streams.video[0]
        frames = [f.to_ndarray(format="rgb24") for f in container.decode(stream)]
        codec, shape = stream.codec_context.name, (stream.width, stream.height)
    return Rendered(bag, video, result.stderr, frames, codec, shape)


def _mad(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a.astype(np.int16) - b).mean())


def test_sixty_seconds_at_one_fps_are_sixty_frames_that_decode(rendered: Rendered) -> None:
    assert len(rendered.frames) == DURATION_S * FPS
    assert rendered.codec == "h264" and rendered.size == SIZE
    assert all(f.shape == (SIZE[1], SIZE[0], 3) for f in rendered.frames)
    assert f"{DURATION_S * FPS} frames ({DURATION_S:.1f} s at {FPS} fps, 640x360) of '3D: " in rendered.stderr
    assert rendered.stderr.count("lavapipe") <= 1  # said once, when it falls back
    assert not list(rendered.video.parent.glob(".*partial"))


def test_frames_change_where_the_robot_moves_and_not_where_it_holds_still(rendered: Rendered) -> None:
    steps = [_mad(a, b) for a, b in zip(rendered.frames, rendered.frames[1:], strict=False)]
    first, last = int(MOVING_S[0] * FPS), int(MOVING_S[1] * FPS)  # frame k is at k / FPS s
    assert max(steps[:first]) <= STILL_LEVELS, steps[:first]  # frames 0…20: nothing moved yet
    assert min(steps[first:last]) >= MOVING_LEVELS, steps[first:last]  # 20…40: swivel turns, the base drives
    assert max(steps[last:]) <= STILL_LEVELS, steps[last:]  # 40…59: held where it got to
    assert _mad(rendered.frames[0], rendered.frames[-1]) > 2 * MOVING_LEVELS


def _runs(mask: np.ndarray) -> np.ndarray:
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    return edges.reshape(-1, 2)


def _view_rect(img: np.ndarray) -> tuple[int, int, int, int]:
    """The 3D view in a whole-viewer screenshot: the longest row of its #303030 background (the sky above the
    grid), and down the middle of that row, the run of pixels that are not the panels' #0d0d0d."""
    sky = np.all(img == 0x30, axis=2)
    y = int(sky.sum(1).argmax())
    x0, x1 = max(_runs(sky[y]), key=lambda r: int(r[1] - r[0]))
    column = np.abs(img[:, (x0 + x1) // 2].astype(np.int16) - 0x0D).max(1) > 3
    y0, y1 = next(r for r in _runs(column) if r[0] <= y < r[1])
    return int(x0), int(y0), int(x1), int(y1)


def _likeness(frame: np.ndarray, view: np.ndarray, height: int = 72) -> tuple[float, float]:
    """Mean absolute difference and correlation (grey) of ``frame`` cut to ``view``'s aspect and ``view``, both
    scaled to ``height`` pixels."""
    vh, vw = view.shape[:2]
    width = round(height * vw / vh)
    fh, fw = frame.shape[:2]
    cut = round(fh * vw / vh)
    x = (fw - cut) // 2
    a = np.asarray(Image.fromarray(view).resize((width, height), Image.Resampling.BOX), float)
    b = np.asarray(Image.fromarray(frame[:, x : x + cut]).resize((width, height), Image.Resampling.BOX), float)
    return float(np.abs(a - b).mean()), float(np.corrcoef(a.mean(2).ravel(), b.mean(2).ravel())[0, 1])


def test_a_frame_looks_like_the_native_viewers_screenshot(
    rendered: Rendered, x_display: viewers.XDisplay, artifacts_dir: Path
) -> None:
    rrd = artifacts_dir / "moving.rrd"
    result = cli("--bag", str(rendered.bag), "--save", str(rrd))
    assert result.returncode == 0, result.stderr
    shot = viewers.screenshot_native(
        rrd,
        artifacts_dir / "native.png",
        display=x_display.display,
        window_size=(1600, 1000),  # the toasts (Docker, lavapipe) sit over the plots, not the 3D view
    )
    native = viewers.load_png(shot.path)
    x0, y0, x1, y1 = _view_rect(native)
    view = native[y0:y1, x0:x1]
    Image.fromarray(view).save(artifacts_dir / "native_view.png")
    Image.fromarray(rendered.frames[10]).save(artifacts_dir / "frame_10s.png")
    assert (x1 - x0) > 300 and (y1 - y0) > 300, (x0, y0, x1, y1)  # the 3D view, not a sliver of another one
    levels, correlation = _likeness(rendered.frames[10], view)  # 10 s: still, as at the native viewer's start
    assert levels <= 5.0 and correlation >= 0.9, (levels, correlation)
    moved_levels, moved_correlation = _likeness(rendered.frames[-1], view)  # 59 s: the robot drove 2 m away
    assert moved_levels > 5.0 or moved_correlation < 0.9, (moved_levels, moved_correlation)


def test_an_unknown_view_is_one_line_naming_the_views(rendered: Rendered) -> None:
    out = rendered.video.with_name("unknown.mp4")
    result = cli("--bag", str(rendered.bag), "--duration", "1", "--render", str(out), "--view", "camera", timeout=300)
    assert result.returncode == 2, result.stderr
    last = result.stderr.splitlines()[-1]
    assert last.startswith("error: --view 'camera' is not a view of the layout; the views: ") and "'Warnings'" in last
    assert "Traceback" not in result.stderr and not out.exists()


def test_without_an_adapter_of_its_own_lavapipe_is_offered_alone(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """A Vulkan loader pointed at a missing driver (as on a machine whose only ICD is broken or absent): the first
    viewer finds no adapter and exits; the render goes on with Mesa's lavapipe alone, and says it draws on the CPU."""
    from r2d2_viz.viewer.files.render import rendering

    if viewers.lavapipe_icd() is None:
        pytest.skip("Mesa's lavapipe (mesa-vulkan-drivers) is not installed")
    rrd = tmp_path / "lap.rrd"
    assert cli("--save", str(rrd), "--duration", "1").returncode == 0
    monkeypatch.setenv("VK_ICD_FILENAMES", str(tmp_path / "no-such-driver.json"))
    monkeypatch.setenv("WGPU_BACKEND", "vulkan")
    with rendering(rrd, (160, 96), None) as renderer:
        assert renderer.software
        assert renderer.span is not None
        frame = renderer.frame(renderer.span.end)
    assert frame.shape == (96, 160, 3), frame.shape  # the window sized to leave the view 160x96
    assert frame.std() > 5  # drawn: the grid and the robot, not a flat colour
