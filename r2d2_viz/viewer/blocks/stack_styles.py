"""The properties of nav2's ParticleCloud and vision_msgs' Detection3DArray displays as decode options (their
plugins' ranges: Alpha 0-1 (Detection3DArray: 0.1-1), Line Width 0.01-0.1 m, Min Arrow Length ≤ Max)."""

from __future__ import annotations

from typing import Any

from r2d2_viz.msgs.shapes import DecodeOptions
from r2d2_viz.rviz.spec import DisplayStyleSpec

SHAPES = ("Arrow (Flat)", "Arrow (3D)", "Axes")


def stack_options(s: DisplayStyleSpec) -> dict[str, Any]:
    """The :class:`DecodeOptions` fields a display's properties set (what it leaves unset keeps the default)."""
    out: dict[str, Any] = {}
    alpha = None if s.alpha is None else min(max(s.alpha, 0.0), 1.0)
    if s.color is not None or alpha is not None:
        out["display_color"] = (*(s.color or (255, 25, 0)), round(255 * (1.0 if alpha is None else alpha)))
    if alpha is not None:
        out["alpha"] = max(alpha, 0.1)
    if s.shape in SHAPES:
        out["particle_shape"] = s.shape
    low, high = s.arrow_lengths
    if low is not None or high is not None:
        default_low, default_high = DecodeOptions().arrow_lengths
        low = max(default_low if low is None else low, 0.0)
        out["arrow_lengths"] = (low, max(default_high if high is None else high, low))
    if s.only_edge is not None:
        out["only_edge"] = s.only_edge
    if s.size is not None and s.size > 0:
        out["line_width"] = min(max(s.size, 0.01), 0.1)
    return out
