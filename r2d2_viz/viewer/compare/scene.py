"""What a ``--compare`` recording holds beside its runs: each run's tint, the frame the runs hang from (each run's
fixed frame placed in it: together, or side by side) and the summary as a text document."""

from __future__ import annotations

from collections.abc import Sequence

import rerun as rr

from r2d2_viz.viewer.compare.merge import RUNS, RunStyle

COMPARE_FRAME = "compare"
"""The frame of the 3D view: every run's fixed frame hangs from it."""
SUMMARY = "/compare/summary"
TINTS: tuple[tuple[int, int, int], ...] = (
    (255, 140, 0),
    (30, 144, 255),
    (50, 205, 50),
    (220, 20, 180),
    (255, 215, 0),
    (0, 206, 209),
)
"""The ghosts' tints, in run order (the first run is drawn as it is)."""
GHOST_ALPHA = 100
"""A ghost's opacity (of 255)."""


def tint(k: int) -> tuple[int, int, int, int] | None:
    """The tint of the ``k``-th run (None: the first, drawn as it is)."""
    return None if k == 0 else (*TINTS[(k - 1) % len(TINTS)], GHOST_ALPHA)


def anchor(rec: rr.RecordingStream, style: RunStyle, fixed_frame: str, offset_m: Sequence[float]) -> None:
    """The run's fixed frame placed in :data:`COMPARE_FRAME`, ``offset_m`` (x, y, z) away (``--side-by-side``)."""
    rec.log(
        f"{RUNS}/{style.name}/anchor",
        rr.Transform3D(translation=list(offset_m), parent_frame=COMPARE_FRAME, child_frame=style.frame(fixed_frame)),
        static=True,
    )


def log_summary(rec: rr.RecordingStream, lines: Sequence[str]) -> None:
    """The summary as a text document (its view: the layout's "Differences")."""
    rec.log(SUMMARY, rr.TextDocument("\n".join(lines), media_type=rr.MediaType.TEXT), static=True)
