"""RViz's colour maps: the Intensity transformer's rainbow and the Map display's palettes.

Sources (ros2/rviz, rviz_default_plugins): ``intensity_pc_transformer.cpp`` (autocomputed min/max, value =
1 - (v - min) / (max - min), then ``getRainbowColor``) and ``displays/map/palette_builder.cpp``.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from r2d2_viz.msgs.shapes import F32, U8

_N, _0, _1 = (0.0, 1.0), (0.0, 0.0), (1.0, 0.0)
_SEXTANTS = [  # getRainbowColor's (r, g, b) for i = 0..6 (0 and 1 alike: v clipped to [0, 1] gives i >= 1)
    (_N, _0, _1),
    (_N, _0, _1),
    (_0, _N, _1),
    (_0, _1, _N),
    (_N, _1, _0),
    (_1, _N, _0),
    (_1, _N, _0),
]
_CONSTANT = [np.array([row[c][0] for row in _SEXTANTS]) for c in range(3)]
_SLOPE = [np.array([row[c][1] for row in _SEXTANTS]) for c in range(3)]


def rainbow(value: F32) -> U8:
    """RViz's ``getRainbowColor`` (HSV hue 0..5/6) of ``value`` clipped to [0, 1] (NaN reads as 0): RGBA8."""
    v = np.clip(np.nan_to_num(np.asarray(value, dtype=np.float64), nan=0.0), 0.0, 1.0)
    h = v * 5.0 + 1.0
    i = np.floor(h).astype(np.int64)
    f = h - i
    n = np.where(i % 2 == 0, f, 1.0 - f)  # 1 - f on even sextants, as getRainbowColor flips f there
    # each channel is one of n, 0 or 1 per sextant i (1..6): constant + slope * n, looked up (no np.select)
    r, g, b = (_CONSTANT[c][i] + _SLOPE[c][i] * n for c in range(3))
    out = np.empty((v.shape[0], 4), dtype=np.uint8)
    out[:, 0], out[:, 1], out[:, 2] = (np.round(c * 255) for c in (r, g, b))
    out[:, 3] = 255
    return out


def intensity_colors(values: F32) -> U8:
    """The Intensity transformer's default: rainbow over the autocomputed [min, max] of the finite values; the
    maximum is magenta, the minimum red. Equal bounds colour everything alike (RViz divides by 1e20)."""
    v = np.asarray(values, dtype=np.float64)
    finite = v[np.isfinite(v)]
    if finite.size == 0:
        return rainbow(np.ones(v.shape[0], dtype=np.float32))
    lo, hi = float(finite.min()), float(finite.max())
    diff = hi - lo if hi > lo else 1e20
    with np.errstate(invalid="ignore", over="ignore"):
        return rainbow((1.0 - (v - lo) / diff).astype(np.float32))


def _palette(kind: Literal["map", "costmap", "raw"]) -> U8:
    p = np.zeros((256, 4), dtype=np.uint8)
    i = np.arange(256)
    if kind == "raw":
        p[:, 0] = p[:, 1] = p[:, 2] = i
        p[:, 3] = 255
        return p
    if kind == "map":
        v = 255 - (255 * i[:101]) // 100
        p[:101] = np.stack([v, v, v, np.full(101, 255)], axis=1)
    else:
        v = (255 * i[1:99]) // 100
        p[1:99] = np.stack([v, np.zeros(98), 255 - v, np.full(98, 255)], axis=1)
        p[99] = (0, 255, 255, 255)
        p[100] = (255, 0, 255, 255)
    p[101:128] = (0, 255, 0, 255)
    j = i[128:255]
    p[128:255] = np.stack([np.full(127, 255), (255 * (j - 128)) // 126, np.zeros(127), np.full(127, 255)], axis=1)
    p[255] = (0x70, 0x89, 0x86, 255)
    return p


PALETTES: dict[str, U8] = {kind: _palette(kind) for kind in ("map", "costmap", "raw")}


def packed_rgb(words: np.ndarray, alpha: bool) -> U8:
    """The RGB8 transformer: ``uint32`` words ``0xAARRGGBB`` (alpha used only for an ``rgba`` field) as RGBA8."""
    w = np.asarray(words, dtype=np.uint32)
    out = np.empty((w.shape[0], 4), dtype=np.uint8)
    out[:, 0] = (w >> 16) & 0xFF
    out[:, 1] = (w >> 8) & 0xFF
    out[:, 2] = w & 0xFF
    out[:, 3] = (w >> 24) & 0xFF if alpha else 255
    return out
