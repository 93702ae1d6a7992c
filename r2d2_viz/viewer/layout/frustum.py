"""RViz's CameraInfo display in the blueprint: the frustum of the camera's pinhole (which the recording holds on
the CameraInfo topic's entity, from ``K`` and the image size) drawn ``Far clip`` metres deep (RViz's default 1 m)
in the display's Color and Alpha (RViz's (85, 255, 255), 0.5) with 1 cm lines (RViz's ``setLineWidth(0.01)``):
a view override of ``Pinhole``'s ``image_plane_distance``, ``color`` and ``line_width``.

RViz (``rviz_default_plugins/displays/camera_info/camera_info_display.cpp``) draws the four rays through the image
corners ``(0, 0), (w, 0), (w, h), (0, h)`` to depth Far clip, the far rectangle as edges (Edge color) and its
polygon (Color, Alpha); Rerun draws the same pyramid as lines only, in one colour: the display's Color.
"""

from __future__ import annotations

import rerun as rr

from r2d2_viz.rviz.spec import ViewSpec

FAR_CLIP = 1.0
COLOR = (85, 255, 255)
ALPHA = 0.5
LINE_WIDTH = 0.01


def frustums(spec: ViewSpec) -> dict[str, rr.Pinhole]:
    """CameraInfo topic entity → its frustum's override, for each enabled CameraInfo display."""
    out = {}
    for display in spec.topics:
        if display.kind != "CameraInfo" or not display.enabled or not display.topic.startswith("/"):
            continue
        s = display.style
        far = s.length if s.length is not None and s.length > 0 else FAR_CLIP
        alpha = min(max(s.alpha if s.alpha is not None else ALPHA, 0.0), 1.0)
        color = (*(s.color or COLOR), round(255 * alpha))
        out[display.topic] = rr.Pinhole.from_fields(image_plane_distance=far, color=color, line_width=LINE_WIDTH)
    return out
