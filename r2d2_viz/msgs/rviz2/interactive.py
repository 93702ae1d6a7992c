"""visualization_msgs/InteractiveMarkerUpdate as RViz's InteractiveMarkers display shows it, display only: each
interactive marker's controls' markers at the marker's pose; a pose update moves them; an erase removes them.

RViz (``rviz_default_plugins/displays/interactive_markers/``): a control's marker with an empty ``frame_id`` is
placed relative to its interactive marker (``T_frame_marker = T_frame_im · T_im_marker``), one with a frame of
its own stays in that frame. Each marker of control ``c`` (k-th marker) is the ``MarkerOp`` keyed
``(<interactive marker name>, c · 1000 + k)``: drawn on ``<topic>/<name>/<key>``, so an erase (and a full
update, which replaces the controls) is a DELETEALL of the name. The menus, the description text, the
interaction handles RViz adds for the mouse and feedback are not drawn (nothing is ever published).
"""

from __future__ import annotations

from typing import Any

from r2d2_viz.msgs.geometry import frame_of, header_of, matrix_quat, pose_of, quat_matrix
from r2d2_viz.msgs.markers import SHAPES
from r2d2_viz.msgs.shapes import Decoded, DecodeOptions, MarkerOp, Pose
from r2d2_viz.msgs.typestore import MsgError, deserialize

UPDATE = "visualization_msgs/msg/InteractiveMarkerUpdate"
MARKERS_PER_CONTROL = 1000
"""A control's markers beyond these are not drawn (their keys would run into the next control's)."""


def compose(a: Pose, b: Pose) -> Pose:
    """``a · b``: the pose ``b`` (given in the frame ``a`` places) in the frame ``a`` is given in."""
    R = quat_matrix(a.xyzw)
    t = R @ list(b.translation) + list(a.translation)
    x, y, z = (float(v) for v in t)
    return Pose((x, y, z), matrix_quat(R @ quat_matrix(b.xyzw)))


def marker_ops(im: Any, pose: Pose, frame: str, stamp: int) -> list[MarkerOp]:
    """The ``add`` ops of one interactive marker's controls' markers at ``pose`` in ``frame``."""
    name = str(im.name)
    ops = []
    for c, control in enumerate(im.controls):
        for k, m in enumerate(control.markers[:MARKERS_PER_CONTROL]):
            shape = SHAPES.get(int(m.type))
            if shape is None:
                raise MsgError(f"interactive marker {name!r}: unknown marker type {m.type}")
            own = pose_of(m.pose)  # in the marker's own frame, else relative to the interactive marker
            here, T_frame_marker = (frame, compose(pose, own))
            if m.header.frame_id:
                here, T_frame_marker = frame_of(m.header.frame_id), own
            drawn = Decoded(here, stamp, (shape(m, T_frame_marker),))
            ops.append(MarkerOp("add", name, c * MARKERS_PER_CONTROL + k, drawn))
    return ops


def update_ops(msg: Any, known: dict[str, Any] | None = None) -> list[MarkerOp]:
    """One update's ops: erases, then the markers (each replaces its name's controls), then pose updates of the
    markers in ``known`` (name → the last InteractiveMarker message of that name, kept up to date; None: pose
    updates are not drawn)."""
    ops = [MarkerOp("deleteall", str(name), 0) for name in msg.erases]
    for name in msg.erases:
        if known is not None:
            known.pop(str(name), None)
    for im in msg.markers:
        frame, stamp = header_of(im)
        ops.append(MarkerOp("deleteall", str(im.name), 0))
        ops += marker_ops(im, pose_of(im.pose), frame, stamp)
        if known is not None:
            known[str(im.name)] = im
    for update in msg.poses:
        im = known.get(str(update.name)) if known is not None else None
        if im is not None:
            frame, stamp = header_of(update)
            ops += marker_ops(im, pose_of(update.pose), frame, stamp)
    return ops


def decode_interactive_update(data: bytes | memoryview, options: DecodeOptions) -> list[MarkerOp]:
    """An InteractiveMarkerUpdate on its own: its erases and markers (its pose updates need the markers of earlier
    updates: :class:`InteractiveMarkers`)."""
    return update_ops(deserialize(data, UPDATE))


class InteractiveMarkers:
    """One topic's interactive markers so far, for its pose updates."""

    def __init__(self) -> None:
        self.known: dict[str, Any] = {}

    def decode(self, data: bytes | memoryview) -> list[MarkerOp]:
        return update_ops(deserialize(data, UPDATE), self.known)
