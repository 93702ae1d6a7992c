"""vision_msgs 4.x Detection3DArray and Detection2DArray.

3D, as ``vision_msgs_rviz_plugins`` ``Detection3DArrayDisplay`` draws it (``detection_3d_common.hpp``): a box per
detection at its ``bbox.center`` pose, ``bbox.size`` (a size under 1e-4 m drawn 1e-4 m), in the array's header
frame, coloured by the class of its highest-scoring result (``getColor``: car (255, 165, 0), person (0, 0, 255),
cyclist (255, 255, 0), motorcycle (230, 230, 250), case aside; any other class (190, 190, 190); none or an empty
id (255, 22, 80)), alpha 1; "Only Edge" draws the twelve edges ``Line Width`` (0.05 m) wide. Each box is labelled
``<class_id> <score>`` (score to two decimals; RViz shows the score alone, with "Show Score").

2D (vision_msgs has no RViz display for it): each detection's ``bbox`` — centre (x, y) in pixels, turned by
``theta`` (rad), ``size_x`` by ``size_y`` — as a closed outline on the image of the same camera, coloured and
labelled the same way.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from r2d2_viz.msgs.geometry import FLOAT32_MAX, header_of, pose_of, xyz
from r2d2_viz.msgs.shapes import Boxes, Decoded, DecodeOptions, Outlines2D, Rgba8
from r2d2_viz.msgs.typestore import MsgError, deserialize

CLASS_COLORS: dict[str, tuple[int, int, int]] = {
    "car": (255, 165, 0),
    "person": (0, 0, 255),
    "cyclist": (255, 255, 0),
    "motorcycle": (230, 230, 250),
}
OTHER_CLASS = (190, 190, 190)
NO_CLASS = (255, 22, 80)
MIN_SIZE = 1e-4
CORNERS = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])


def best(detection: Any) -> tuple[str, float] | None:
    """``(class_id, score)`` of the detection's highest-scoring result (the first of equals), None without any."""
    results = [(str(r.hypothesis.class_id), float(r.hypothesis.score)) for r in detection.results]
    return max(results, key=lambda r: r[1]) if results else None


def color_of(result: tuple[str, float] | None, alpha: float) -> Rgba8:
    """The plugin's colour of a class (its alpha property applied)."""
    rgb = NO_CLASS if result is None or not result[0] else CLASS_COLORS.get(result[0].lower(), OTHER_CLASS)
    return (*rgb, round(255 * min(max(alpha, 0.0), 1.0)))


def label_of(result: tuple[str, float] | None) -> str:
    return "" if result is None else f"{result[0]} {result[1]:.2f}".strip()


def decode_detection3d_array(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """The detections' boxes, oriented, coloured and labelled by class."""
    msg = deserialize(data, "vision_msgs/msg/Detection3DArray")
    frame, stamp = header_of(msg)
    n = len(msg.detections)
    centers, half, q = (np.zeros((n, k), dtype=np.float32) for k in (3, 3, 4))
    colors, labels = np.zeros((n, 4), dtype=np.uint8), []
    for i, detection in enumerate(msg.detections):
        pose = pose_of(detection.bbox.center)
        centers[i], q[i] = pose.translation, pose.xyzw
        half[i] = np.maximum(np.array(xyz(detection.bbox.size)), MIN_SIZE) / 2
        result = best(detection)
        colors[i] = color_of(result, options.alpha)
        labels.append(label_of(result))
    edges = options.line_width if options.only_edge else 0.0
    return Decoded(frame, stamp, (Boxes(centers, half, q, colors, labels=tuple(labels), edges=edges),))


def decode_detection2d_array(data: bytes | memoryview, options: DecodeOptions) -> Decoded:
    """The detections' boxes as outlines in pixels (placed on their camera's image when logged)."""
    msg = deserialize(data, "vision_msgs/msg/Detection2DArray")
    frame, stamp = header_of(msg)
    n = len(msg.detections)
    boxes = np.zeros((n, 5), dtype=np.float64)  # x, y, theta, size x, size y
    colors, labels = np.zeros((n, 4), dtype=np.uint8), []
    for i, detection in enumerate(msg.detections):
        b = detection.bbox
        boxes[i] = (b.center.position.x, b.center.position.y, b.center.theta, b.size_x, b.size_y)
        result = best(detection)
        colors[i] = color_of(result, options.alpha)
        labels.append(label_of(result))
    if not np.all(np.abs(boxes) <= FLOAT32_MAX):
        raise MsgError("a 2D box with a NaN or infinite value")
    c, s = np.cos(boxes[:, 2]), np.sin(boxes[:, 2])
    local = CORNERS[None, :, :] * boxes[:, None, 3:5]  # (n, 4, 2)
    x = boxes[:, None, 0] + c[:, None] * local[:, :, 0] - s[:, None] * local[:, :, 1]
    y = boxes[:, None, 1] + s[:, None] * local[:, :, 0] + c[:, None] * local[:, :, 1]
    corners = np.stack([x, y], axis=2).astype(np.float32)
    return Decoded(frame, stamp, (Outlines2D(corners, colors, tuple(labels)),))
