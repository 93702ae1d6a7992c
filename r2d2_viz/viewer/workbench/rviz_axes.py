"""RViz's Axes display: three cylinders — x red, y green, z blue — ``Length`` long and ``Radius`` thick from the
origin of its Reference Frame (the fixed frame by default), as ``rviz_rendering::Axes`` draws them
(``rviz_default_plugins/displays/axes/axes_display.cpp``: Length 1 m, Radius 0.1 m by default). Logged once, at
the run's first time, on ``/rviz_axes/<display name>``: the frame places it at every time after."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np
import rerun as rr

from r2d2_viz.msgs.shapes import Cylinders, Decoded
from r2d2_viz.rviz.spec import ViewSpec
from r2d2_viz.viewer.displays import log_decoded
from r2d2_viz.viewer.notices import Notices

LENGTH = 1.0
RADIUS = 0.1
COLORS = np.array([[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]], dtype=np.uint8)
_H = math.sqrt(0.5)
Z_TO_AXES = np.array([[0.0, _H, 0.0, _H], [-_H, 0.0, 0.0, _H], [0.0, 0.0, 0.0, 1.0]], dtype=np.float32)
"""``xyzw`` turning a cylinder's own z onto x (about y, +90°), onto y (about x, -90°), and z itself."""
ROOT = "/rviz_axes"


def axes_drawing(frame: str, length: float = LENGTH, radius: float = RADIUS) -> Decoded:
    """The three cylinders in ``frame`` (centres half way along each axis)."""
    centers = (np.eye(3) * length / 2).astype(np.float32)
    lengths = np.full(3, length, dtype=np.float32)
    radii = np.full(3, radius, dtype=np.float32)
    return Decoded(frame, 0, (Cylinders(centers, lengths, radii, Z_TO_AXES, COLORS),))


def start_view(notices: Notices, notes: Iterable[str], spec: ViewSpec, fixed_frame: str) -> None:
    """Say the run's notes, and draw the config's enabled Axes displays (at the notices' first time)."""
    for note in notes:
        notices.report(note)
    for display in spec.topics:
        if display.kind != "Axes" or not display.enabled:
            continue
        s = display.style
        drawing = axes_drawing(
            s.frame or fixed_frame,
            s.length if s.length is not None and s.length > 0 else LENGTH,
            s.radius if s.radius is not None and s.radius > 0 else RADIUS,
        )
        entity = f"{ROOT}/{rr.escape_entity_path_part(display.name)}"
        log_decoded(notices.rec, entity, drawing, timeline=notices.timeline, time_ns=notices.at_ns, clock=notices.clock)
