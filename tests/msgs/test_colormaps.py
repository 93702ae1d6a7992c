"""RViz's rainbow and map palettes against a transcription of the C++ (msgs_build.rviz_rainbow) and by hand."""

from __future__ import annotations

import numpy as np
from msgs_build import rviz_rainbow

from r2d2_viz.msgs.colormaps import PALETTES, intensity_colors, packed_rgb, rainbow


def test_rainbow_matches_the_transcribed_cpp() -> None:
    values = np.linspace(-0.2, 1.2, 281, dtype=np.float32)
    got = rainbow(values)
    assert [tuple(c[:3]) for c in got.tolist()] == [rviz_rainbow(float(v)) for v in values]
    assert set(got[:, 3].tolist()) == {255}
    # by hand: 0 → h = 1, i = 1 odd, f = 0, n = 1 → (1, 0, 1) magenta; 0.5 → h = 3.5, i = 3, f = 0.5 → (0, 1, 0.5)
    assert rainbow(np.array([0.0, 0.5, 1.0], np.float32))[:, :3].tolist() == [[255, 0, 255], [0, 255, 128], [255, 0, 0]]


def test_rainbow_table_matches_the_transcribed_cpp_at_every_step() -> None:
    # the rainbow is a table lookup (issue 38: it was computed in doubles per point): every level step of every
    # channel, where 255 n crosses k + 1/2 in each sextant, and each sextant's edge, with the float32 values just
    # around it (a wrong step shows as a colour one level off on one side of it)
    k = np.arange(255) + 0.5
    centres = np.concatenate([(s + k / 255) / 5 for s in range(5)] + [np.arange(6) / 5]).astype(np.float32)
    values = (centres.view(np.int32)[:, None] + np.arange(-3, 4, dtype=np.int32)).view(np.float32).ravel()
    values = np.concatenate([values, np.array([np.nan, -np.inf, np.inf, -0.0, 7.0], np.float32)])
    got = [tuple(c[:3]) for c in rainbow(values).tolist()]
    want = [rviz_rainbow(0.0 if np.isnan(v) else float(v)) for v in values]  # NaN reads as 0
    assert got == want


def test_intensity_equal_bounds_and_nan() -> None:
    # equal bounds: RViz divides by 1e20, value 1 for everyone → red
    assert intensity_colors(np.array([5.0, 5.0], np.float32))[:, :3].tolist() == [[255, 0, 0]] * 2
    assert intensity_colors(np.array([np.nan, 0.0, 1.0], np.float32)).shape == (3, 4)


def test_palettes_by_hand() -> None:
    m, c = PALETTES["map"], PALETTES["costmap"]
    assert m[0].tolist() == [255, 255, 255, 255] and m[100].tolist() == [0, 0, 0, 255]
    assert m[120].tolist() == [0, 255, 0, 255] and m[128].tolist() == [255, 0, 0, 255]
    assert m[191].tolist() == [255, 127, 0, 255]  # (255·63) // 126 = 127
    assert c[1].tolist() == [2, 0, 253, 255]  # v = 255 // 100 = 2
    assert c[98].tolist() == [249, 0, 6, 255]  # v = 24990 // 100 = 249


def test_packed_rgb() -> None:
    words = np.array([0xFF102030, 0x00A0B0C0], dtype=np.uint32)
    assert packed_rgb(words, alpha=False).tolist() == [[0x10, 0x20, 0x30, 255], [0xA0, 0xB0, 0xC0, 255]]
    assert packed_rgb(words, alpha=True)[:, 3].tolist() == [255, 0]
