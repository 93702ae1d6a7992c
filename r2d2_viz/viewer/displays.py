"""Log decoded display messages (``r2d2_viz.msgs``) to Rerun, each in its TF frame (``CoordinateFrame``).

A message's drawings go on its topic's entity (one item) or on ``<entity>/<i>`` (several); the item pose
``T_frame_item`` is an ``InstancePoses3D``. Markers go on ``<entity>/<ns>/<id>`` (``_`` for an empty ns); DELETE,
DELETEALL and an expired lifetime ``Clear`` the markers shown (recursively), the expiry at its own time.

Every entity stays in a TF frame at every time of the run, drawn or not (an entity without one is in Rerun's
implicit ``tf#/<path>`` frame, which no transform reaches: the view reports it): a marker entity sits in the
fixed frame (the book's anchor) from the anchor's time until it is drawn, and again after each ``Clear``. A
camera's pinhole names its frames (parent: the optical frame; child: ``<entity>#image``, its image plane).

What is not drawn in 3D (logs, statuses, numbers, fixes) goes on entities in no frame:
:mod:`r2d2_viz.viewer.blocks.plain_log`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import rerun as rr

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.shapes import Decoded, MarkerOp, Pose, is_plain
from r2d2_viz.viewer.blocks.plain_log import PlainBook, log_plain
from r2d2_viz.viewer.blocks.recorder import NUMBERS, Recorder

Clock = Literal["duration", "timestamp"]
MeshLoader = Callable[[str], "tuple[bytes, str] | None"]
"""``uri`` → (file bytes, media type), or None when the mesh cannot be found."""
TEXT_RADIUS = 0.01
QUAD = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


@dataclass
class MarkerBook:
    """The markers drawn per topic entity: marker entity → expiry time in ns (None: no lifetime)."""

    live: dict[str, int | None] = field(default_factory=dict)
    frames: dict[str, str] = field(default_factory=dict)
    """Every marker entity drawn so far → the frame it was last drawn in."""
    drawn: set[str] = field(default_factory=set)
    """The marker entities drawn and not cleared since."""
    anchor: tuple[int, str] | None = None
    """(time, frame) where the topic's entities were placed before their first message (the display feed's)."""


def set_time(rec: Recorder, timeline: str, time_ns: int, clock: Clock) -> None:
    """Set ``timeline`` to ``time_ns``, as a duration or as a timestamp."""
    if not isinstance(rec, rr.RecordingStream):
        rec.at(time_ns)
    elif clock == "duration":
        rec.set_time(timeline, duration=np.timedelta64(time_ns, "ns"))
    else:
        rec.set_time(timeline, timestamp=np.datetime64(time_ns, "ns"))


def marker_entity(entity_path: str, ns: str, key: int | None = None) -> str:
    """``<entity>/<ns>[/<id>]`` with ``ns`` escaped (``_`` when empty)."""
    path = f"{entity_path}/{rr.escape_entity_path_part(ns) if ns else '_'}"
    return path if key is None else f"{path}/{key}"


def instance_pose(pose: Pose, scale: tuple[float, float, float] | None = None) -> rr.InstancePoses3D:
    """The item's pose in its frame (``xyzw``), with an optional scale applied first."""
    return rr.InstancePoses3D(
        translations=[pose.translation], quaternions=[pose.xyzw], scales=None if scale is None else [scale]
    )


def _grid(item: shapes.GridMap) -> list[rr.AsComponents]:
    h, w = item.rgba.shape[:2]
    x, y = w * item.resolution, h * item.resolution
    return [
        rr.Mesh3D(
            vertex_positions=[[0, 0, 0], [x, 0, 0], [x, y, 0], [0, y, 0]],
            triangle_indices=QUAD,
            vertex_texcoords=[[0, 0], [1, 0], [1, 1], [0, 1]],  # texture row 0 (grid row 0) at y = 0
            albedo_texture=item.rgba,
        ),
        instance_pose(item.T_frame_item),
    ]


def _mesh(item: shapes.MeshResource, load: MeshLoader | None) -> list[rr.AsComponents]:
    found = load(item.uri) if load is not None else None
    if found is None:  # unresolved: a labelled point where the mesh would be
        return [
            rr.Points3D([[0, 0, 0]], labels=[item.uri], show_labels=True, radii=TEXT_RADIUS),
            instance_pose(item.T_frame_item),
        ]
    blob, media_type = found
    return [
        rr.Asset3D(contents=blob, media_type=media_type, albedo_factor=item.color),
        instance_pose(item.T_frame_item, item.scale),
    ]


def packed(colors: np.ndarray) -> np.ndarray:
    """RGBA8 rows ``(n, 4)`` as ``0xRRGGBBAA`` uint32, what Rerun stores (it would convert them itself, slower)."""
    if colors.dtype != np.uint8 or colors.ndim != 2 or colors.shape[1] != 4:
        return colors
    packed: np.ndarray = np.ascontiguousarray(colors).view(">u4").ravel().astype(np.uint32)
    return packed


def archetypes(item: shapes.Shape, load: MeshLoader | None = None) -> list[rr.AsComponents]:
    """The Rerun archetypes drawing one shape (without its ``CoordinateFrame``)."""
    if isinstance(item, shapes.Points):
        points = rr.Points3D(item.positions, colors=packed(item.colors), radii=item.radius)
        return [points, instance_pose(item.T_frame_item)]
    if isinstance(item, shapes.LineStrips):
        radii = item.radius if item.radius > 0 else None
        strips = item.strips if isinstance(item.strips, np.ndarray) else list(item.strips)  # (N, M, 3): one array
        return [rr.LineStrips3D(strips, colors=item.colors, radii=radii), instance_pose(item.T_frame_item)]
    if isinstance(item, shapes.Arrows):
        arrows = rr.Arrows3D(origins=item.origins, vectors=item.vectors, colors=item.colors, radii=item.radius)
        return [arrows, instance_pose(item.T_frame_item)]
    if isinstance(item, shapes.Boxes) and (item.labels or item.edges):  # detections: labelled, maybe edges only
        boxes = rr.Boxes3D(
            centers=item.centers,
            half_sizes=item.half_sizes,
            quaternions=item.xyzw,
            colors=item.colors,
            labels=list(item.labels) or None,
            show_labels=bool(item.labels),
            radii=item.edges / 2 if item.edges else None,
            fill_mode="majorwireframe" if item.edges else "solid",
        )
        return [boxes, instance_pose(item.T_frame_item)]
    if isinstance(item, (shapes.Boxes, shapes.Ellipsoids)):
        cls = rr.Boxes3D if isinstance(item, shapes.Boxes) else rr.Ellipsoids3D
        solid = cls(
            centers=item.centers,
            half_sizes=item.half_sizes,
            quaternions=item.xyzw,
            colors=item.colors,
            fill_mode="solid",
        )
        return [solid, instance_pose(item.T_frame_item)]
    if isinstance(item, shapes.Outlines2D):  # closed: the first corner again
        closed = np.concatenate([item.corners, item.corners[:, :1]], axis=1)
        return [rr.LineStrips2D(closed, colors=item.colors, labels=list(item.labels), show_labels=True)]
    if isinstance(item, shapes.Cylinders):
        cylinders = rr.Cylinders3D(
            lengths=item.lengths,
            radii=item.radii,
            centers=item.centers,
            quaternions=item.xyzw,
            colors=item.colors,
            fill_mode="solid",
        )
        return [cylinders, instance_pose(item.T_frame_item)]
    if isinstance(item, shapes.TriangleMesh):
        per_vertex = item.colors.shape[0] == item.vertices.shape[0] and item.colors.shape[0] > 1
        mesh = rr.Mesh3D(
            vertex_positions=item.vertices,
            triangle_indices=item.indices,
            vertex_colors=item.colors if per_vertex else None,
            albedo_factor=None if per_vertex or item.colors.shape[0] == 0 else item.colors[0],
        )
        return [mesh, instance_pose(item.T_frame_item)]
    if isinstance(item, shapes.Text):
        label = rr.Points3D(
            [item.position], labels=[item.text], show_labels=True, colors=[item.color], radii=TEXT_RADIUS
        )
        return [label, instance_pose(item.T_frame_item)]
    if isinstance(item, shapes.MeshResource):
        return _mesh(item, load)
    if isinstance(item, shapes.Image):
        return [rr.Image(item.pixels, color_model=item.color_model)]
    if isinstance(item, shapes.CompressedImage):
        return [rr.EncodedImage(contents=item.data, media_type=item.media_type)]
    if isinstance(item, shapes.VideoSample):  # its codec is logged statically, once per entity (display_feed)
        return [rr.VideoStream.from_fields(sample=item.data, is_keyframe=item.keyframe)]
    if isinstance(item, shapes.Pinhole):
        resolution = [item.width, item.height]
        return [rr.Pinhole(image_from_camera=item.K, resolution=resolution, camera_xyz=rr.ViewCoordinates.RDF)]
    if isinstance(item, shapes.GridMap):
        return _grid(item)
    return []  # logs, states, plots, fixes: on entities of their own (:func:`log_plain`)


Prepared = list[tuple[str, list[rr.AsComponents]]]
"""A decoded message's archetypes, built ahead: per item, its entity's suffix and what is logged there."""


def image_plane(entity_path: str) -> str:
    """The frame of the image plane of the camera logged on ``entity_path`` (its pinhole's child frame)."""
    return f"{entity_path}#image"


def _components(item: shapes.Shape, decoded: Decoded, entity: str, load: MeshLoader | None) -> list[rr.AsComponents]:
    if isinstance(item, shapes.Pinhole) and decoded.frame_id:  # optical frame → image plane, named
        plane = image_plane(entity)
        pinhole = rr.Pinhole(
            image_from_camera=item.K,
            resolution=[item.width, item.height],
            camera_xyz=rr.ViewCoordinates.RDF,
            parent_frame=decoded.frame_id,
            child_frame=plane,
        )
        return [rr.CoordinateFrame(plane), pinhole]
    in_3d = not isinstance(item, (shapes.Image, shapes.CompressedImage, shapes.VideoSample))
    frame: list[rr.AsComponents] = [rr.CoordinateFrame(decoded.frame_id)] if in_3d and decoded.frame_id else []
    return [*frame, *archetypes(item, load)]


def prepare(decoded: Decoded, load: MeshLoader | None = None) -> Prepared | None:
    """The archetypes of every item of ``decoded`` (pure: a bag's reader thread builds them beside the logging);
    None when they depend on the entity they go to (a camera's pinhole names its image plane by it)."""
    if any(isinstance(i, shapes.Pinhole | shapes.Plain) for i in decoded.items) or all(
        isinstance(i, NUMBERS) for i in decoded.items
    ):
        return None  # plain items: as their topic's book says; NUMBERS: rows of numbers (viewer/blocks/row_items)
    many = len(decoded.items) > 1
    return [(f"/{i}" if many else "", _components(item, decoded, "", load)) for i, item in enumerate(decoded.items)]


def _log_items(
    rec: Recorder,
    entity_path: str,
    decoded: Decoded,
    load: MeshLoader | None,
    prepared: Prepared | None = None,
    plain: PlainBook | None = None,
) -> None:
    if prepared is not None:
        for suffix, components in prepared:
            rec.log(entity_path + suffix, *components)
        return
    drawn = [item for item in decoded.items if not is_plain(item)]
    many = len(drawn) > 1
    for i, item in enumerate(drawn):
        entity = f"{entity_path}/{i}" if many else entity_path
        if isinstance(rec, rr.RecordingStream) or not rec.take(entity, item, decoded.frame_id):
            rec.log(entity, *_components(item, decoded, entity, load))
    for item in decoded.items:
        if isinstance(item, shapes.LogLine | shapes.Statuses | shapes.Series | shapes.GeoPoint):
            log_plain(rec, entity_path, item, plain if plain is not None else PlainBook())


def expire_markers(rec: Recorder, book: MarkerBook, timeline: str, time_ns: int, clock: Clock) -> None:
    """Clear (at their expiry time) the markers whose lifetime has run out by ``time_ns``."""
    expired = sorted((t, e) for e, t in book.live.items() if t is not None and t <= time_ns)
    for expiry, entity in expired:
        set_time(rec, timeline, expiry, clock)
        _clear(rec, entity, book)
        del book.live[entity]


def _clear(rec: Recorder, prefix: str, book: MarkerBook) -> None:
    """Clear the drawn marker entities at and below ``prefix``, one by one (those cleared already stay so: a
    tracker's DELETEALL costs as many rows as it has markers shown, however many ids it has used), each put back
    in the anchor's frame (the fixed frame; without an anchor, its own): it draws nothing, and the view can place
    it (an entity with no frame is in Rerun's implicit ``tf#/<path>``, which the view reports)."""
    for entity in sorted(e for e in book.drawn if e == prefix or e.startswith(prefix + "/")):
        rec.log(entity, rr.Clear(recursive=True))
        frame = book.anchor[1] if book.anchor is not None else book.frames.get(entity)
        if frame:
            rec.log(entity, rr.CoordinateFrame(frame))
        book.drawn.discard(entity)


def _place(rec: Recorder, entity: str, frame: str, book: MarkerBook, when: tuple[str, int, Clock]) -> None:
    """A marker entity's first drawing at ``when`` (timeline, time, clock): before it, from the anchor's time on,
    the entity sits in the anchor's frame (the fixed frame), like the topic's own entity."""
    timeline, time_ns, clock = when
    if entity not in book.frames and book.anchor is not None and book.anchor[0] < time_ns:
        set_time(rec, timeline, book.anchor[0], clock)
        rec.log(entity, rr.CoordinateFrame(book.anchor[1]))
        set_time(rec, timeline, time_ns, clock)
    book.frames[entity] = frame
    book.drawn.add(entity)


def _log_markers(
    rec: Recorder,
    entity_path: str,
    ops: list[MarkerOp],
    book: MarkerBook,
    load: MeshLoader | None,
    when: tuple[str, int, Clock],
) -> None:
    for op in ops:
        if op.action == "deleteall":
            prefix = marker_entity(entity_path, op.ns) if op.ns else entity_path
            _clear(rec, prefix, book)
            for entity in [e for e in book.live if e == prefix or e.startswith(prefix + "/")]:
                del book.live[entity]
            continue
        entity = marker_entity(entity_path, op.ns, op.id)
        if op.action == "delete" or op.decoded is None:
            _clear(rec, entity, book)
            book.live.pop(entity, None)
            continue
        _place(rec, entity, op.decoded.frame_id, book, when)
        _log_items(rec, entity, op.decoded, load)
        book.live[entity] = None


def log_decoded(
    rec: Recorder,
    entity_path: str,
    decoded: Decoded | list[MarkerOp],
    *,
    timeline: str,
    time_ns: int,
    clock: Clock = "timestamp",
    markers: MarkerBook | None = None,
    load_mesh: MeshLoader | None = None,
    prepared: Prepared | None = None,
    plain: PlainBook | None = None,
) -> None:
    """Log one decoded message on ``entity_path`` at ``time_ns`` (its archetypes ``prepared`` ahead, if they
    were). Marker messages need the topic's ``markers`` book (for DELETEALL and lifetimes); markers that expired
    before ``time_ns`` are cleared first. Logs, states and plots (:data:`~r2d2_viz.msgs.shapes.Plain`) need the
    topic's ``plain`` book."""
    if isinstance(decoded, Decoded):
        set_time(rec, timeline, time_ns, clock)
        _log_items(rec, entity_path, decoded, load_mesh, prepared, plain)
        return
    book = markers if markers is not None else MarkerBook()
    expire_markers(rec, book, timeline, time_ns, clock)
    set_time(rec, timeline, time_ns, clock)
    _log_markers(rec, entity_path, decoded, book, load_mesh, (timeline, time_ns, clock))
    for op in decoded:
        if op.action == "add" and op.lifetime_ns > 0:
            book.live[marker_entity(entity_path, op.ns, op.id)] = time_ns + op.lifetime_ns
