"""scripts/make_screenshots.py without a viewer: its frame times, crop box, GIF assembly and set-up errors.

The renders themselves need Xvfb + lavapipe and minutes; the script is run by hand (see its docstring).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "make_screenshots.py"


@pytest.fixture(scope="module")
def ms() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_screenshots", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses / typing look the module up by name
    spec.loader.exec_module(module)
    return module


def test_lap_times_are_recorded_frames_spread_over_the_lap(ms: ModuleType) -> None:
    times = ms.lap_times(1440, 144)
    assert len(times) == 144 and times[0] == 0.0
    frames = np.array(times) * 30
    assert np.allclose(frames, np.round(frames)) and np.all(np.diff(np.round(frames)) == 10)
    assert ms.lap_times(1440, 36)[-1] == pytest.approx(1400 / 30)


def test_robot_mask_ignores_floor_and_grid(ms: ModuleType) -> None:
    img = np.full((4, 3, 3), 48, dtype=np.uint8)
    img[1, 0] = (110, 110, 113)  # grid
    img[2, 1] = (235, 235, 235)  # robot
    img[3, 2] = (220, 30, 220)  # TF line
    assert ms.robot_mask(img).tolist() == [
        [False, False, False],
        [False, False, False],
        [False, True, False],
        [False, False, True],
    ]


def test_crop_box_holds_every_frame_with_margin_at_the_aspect(ms: ModuleType) -> None:
    a, b = np.zeros((900, 926), bool), np.zeros((900, 926), bool)
    a[300:400, 200:260] = True
    b[500:620, 600:680] = True
    x0, y0, x1, y1 = ms.crop_box([a, b], margin=0.25, aspect=4 / 3)
    assert x0 <= 200 and y0 <= 300 and x1 >= 680 and y1 >= 620
    assert 0 <= x0 and 0 <= y0 and x1 <= 926 and y1 <= 900
    assert (x1 - x0) / (y1 - y0) == pytest.approx(4 / 3, abs=0.01)
    empty = np.zeros((10, 20), bool)
    assert ms.crop_box([empty]) == (0, 0, 20, 10)
    full = np.ones((10, 20), bool)
    assert ms.crop_box([full]) == (0, 0, 20, 10)  # never outside the image


def test_make_gif_writes_every_frame_scaled_and_looping(ms: ModuleType, tmp_path: Path) -> None:
    from PIL import Image, ImageSequence

    frames = []
    for i in range(5):
        img = np.full((300, 400, 3), 48, dtype=np.uint8)
        img[100:150, 50 + 40 * i : 90 + 40 * i] = 240
        frames.append(Image.fromarray(img))
    out = tmp_path / "lap.gif"
    ms.make_gif(frames, out, width=200, fps=15)
    with Image.open(out) as gif:
        assert gif.size == (200, 150) and gif.n_frames == 5 and gif.info["loop"] == 0
        assert gif.info["duration"] == ms.gif_frame_ms(15) == 70
        firsts = [np.asarray(f.convert("RGB"))[60, 40 + 20 * i] for i, f in enumerate(ImageSequence.Iterator(gif))]
    assert all(int(px.min()) > 200 for px in firsts)  # the white block moved with each frame


def test_missing_prerequisites_exit_2_with_the_reason(
    ms: ModuleType, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(ms.viewers, "missing_native_prerequisites", lambda: ["Xvfb not found on PATH (apt-get …)"])
    assert ms.main(["--out", "unused"]) == 2
    err = capsys.readouterr().err
    assert "cannot make screenshots here" in err and "Xvfb not found" in err
