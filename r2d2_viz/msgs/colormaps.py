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


def _rainbow_float(v: np.ndarray) -> np.ndarray:
    """``getRainbowColor`` computed in doubles for values in [0, 1]: RGB levels ``(n, 3)`` (what the table holds)."""
    h = v * 5.0 + 1.0
    i = np.floor(h).astype(np.int64)
    f = h - i
    n = np.where(i % 2 == 0, f, 1.0 - f)  # 1 - f on even sextants, as getRainbowColor flips f there
    # each channel is one of n, 0 or 1 per sextant i (1..6): constant + slope * n, looked up (no np.select)
    return np.stack([np.round((_CONSTANT[c][i] + _SLOPE[c][i] * n) * 255) for c in range(3)], axis=1)


def _rainbow_table() -> tuple[F32, np.ndarray]:
    """The rainbow as a step function of a float32 value: the sorted float32 values where the colour changes, and
    the colour (RGBA8 packed in a native ``uint32``, bytes in R, G, B, A order) below the first and from each.

    Each channel's level changes where ``255 n`` crosses ``k + 1/2`` (and at the sextants' edges): the exact float32
    value of each change is found among the 33 floats around where it falls in exact arithmetic (doubles err by
    far less). The colour is monotone in the value between changes, so the table is exact for every float32."""
    k = np.arange(255) + 0.5
    near = [((s + k / 255) / 5) for s in range(5)] + [np.arange(1, 5) / 5]
    centres = np.concatenate(near).astype(np.float32).view(np.int32)
    floats = (centres[:, None] + np.arange(-16, 17, dtype=np.int32)).view(np.float32)
    floats = np.unique(np.clip(floats, 0.0, 1.0))
    levels = _rainbow_float(floats.astype(np.float64))
    changes = np.flatnonzero((levels[1:] != levels[:-1]).any(axis=1)) + 1
    bounds = floats[changes]
    rgb = np.concatenate([levels[:1], levels[changes]]).astype(np.uint8)
    rgba = np.concatenate([rgb, np.full((len(rgb), 1), 255, np.uint8)], axis=1)
    return bounds.astype(np.float32), np.ascontiguousarray(rgba).view(np.uint32).ravel()


_BOUNDS, _COLORS = _rainbow_table()
_CELLS = 8192
"""[0, 1] cut in this many cells (a power of two: ``v * _CELLS`` is exact), each holding one change at most."""
_FIRST = np.searchsorted(_BOUNDS, np.arange(_CELLS + 1, dtype=np.float32) / _CELLS, side="right")
"""Per cell, the colour at its start (an index into ``_COLORS``); the last cell is 1.0 itself."""
_NEXT = np.append(_BOUNDS, np.float32(np.inf))[_FIRST]
"""Per cell, the change that may fall in it (inf when none: the last)."""
assert (np.diff(_FIRST) <= 1).all(), "a cell holds two changes"


def rainbow(value: F32) -> U8:
    """RViz's ``getRainbowColor`` (HSV hue 0..5/6) of ``value`` clipped to [0, 1] (NaN reads as 0): RGBA8.

    Looked up (:func:`_rainbow_table`): the colour of the value's cell, or of the change in that cell when the
    value is past it — what doubles give for the float32 value, to the level."""
    v = np.asarray(value, dtype=np.float32)
    v = np.fmin(np.fmax(v, np.float32(0.0)), np.float32(1.0))  # fmax: NaN → 0
    cell = (v * np.float32(_CELLS)).astype(np.intp)
    index = _FIRST[cell] + (v >= _NEXT[cell])
    colors: U8 = _COLORS[index].view(np.uint8).reshape(-1, 4)
    return colors


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
