"""Runs of display messages sent as columns (issue 38: one ``rec.log`` per message, its archetypes built per
message, cost more than reading the bag).

A message whose decoding is one :class:`~r2d2_viz.msgs.shapes.Image`, ``CompressedImage`` or ``Points`` in a named
frame, on a topic drawn with one entity (no history, no decay, no ``--video``), is not logged at once: it joins its
topic's run, and the run goes out as one ``rr.send_columns`` — the very components ``rec.log`` of
:func:`r2d2_viz.viewer.displays.archetypes` gives (``CoordinateFrame``, ``Points3D`` positions / colours / radius,
``InstancePoses3D``; ``Image`` buffer and format; ``EncodedImage`` blob and media type), a row per message at its
time. The pixels of a run are copied once, into the one buffer their column is; nothing else is.

What Rerun stamps on ``rec.log`` rows and not on columns: the ``log_time`` / ``log_tick`` timelines (when the
program logged them), as the robot's and the transforms' columns already lack them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from functools import cache, lru_cache

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.shapes import Decoded, MarkerOp, Shape
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.viewer.columns import Encoded, encoded, send, time_array
from r2d2_viz.viewer.displays import Clock, image_plane, packed, set_time

KINDS = (shapes.Image, shapes.CompressedImage, shapes.Points, shapes.Arrows, shapes.Pinhole)
_ONE = np.ones(1, dtype=np.int64)
_BLOB = pa.list_(pa.field("item", pa.uint8(), nullable=False))
RUN_BYTES = 2 << 20
"""A run is sent once its messages hold this many bytes (their points are joined into one column when it goes, and
Rerun keeps a chunk whole until it is written: a window's scans in one run raised ``--topics /scan …``'s peak by
~60 MB), or :data:`RUN_ROWS` messages."""
Column = tuple[rr.ComponentDescriptor, pa.Array]
RUN_ROWS = 4096
"""The most messages a run holds before it is sent."""
HELD_BYTES = 16 << 20
"""A batch run (``hold``) keeps its runs across windows, every run sent once they hold this many bytes in all: a
run per window made a chunk of one row per window for each slot of a history (7,600 of the sensor bag's 16,815
chunks were odometry's), and Rerun keeps ~3 kB of every chunk in memory until the file's footer is written."""


def columnable(decoded: Decoded | list[MarkerOp] | MsgError | None, *, first: bool = False) -> bool:
    """Whether a decoded message can join a run: one image, one set of points or one camera's pinhole (not its
    topic's ``first``: that one is logged from the run's start too), in a named frame."""
    if not isinstance(decoded, Decoded) or not decoded.frame_id or len(decoded.items) != 1:
        return False
    return isinstance(decoded.items[0], KINDS) and not (first and isinstance(decoded.items[0], shapes.Pinhole))


@dataclass
class _Run:
    times_ns: list[int] = field(default_factory=list)
    frames: list[str] = field(default_factory=list)
    items: list[Shape] = field(default_factory=list)
    nbytes: int = 0
    pins: bool = False
    """Whether an item is a view of its message's bytes (an image; a cloud of x, y, z alone): holding it across
    windows would keep the whole block it was read in (a .db3's are anonymous memory: 3 GB held)."""


class ColumnRuns:
    """The runs not sent yet, per entity; ``last_ns``: the time of the latest message taken since :meth:`interrupt`
    (a per-message log then sets the recording's time to it first, as logging that message would have)."""

    def __init__(self, rec: rr.RecordingStream, timeline: str, clock: Clock, *, hold: bool = False) -> None:
        self.rec, self.timeline, self.clock = rec, timeline, clock
        self.runs: dict[str, _Run] = {}
        self.last_ns: int | None = None
        self.hold, self.held = hold, 0
        """``hold``: runs are kept across :meth:`interrupt` s that name no entity (a batch run; a live one sends
        what it has taken at the end of each window); ``held``: the bytes of the messages in the runs."""

    def add(
        self, message: TopicMessage, entity: str, images: tuple[str, ...] = (), *, header_time: bool = False
    ) -> None:
        """Add a message that can join (:func:`columnable`) to the run of ``entity`` (its topic's, or a slot of its
        history), at its receive time or (``header_time``) its header's stamp when it has one; a camera's pinhole to
        its ``images`` ' runs too."""
        decoded = message.decoded
        assert isinstance(decoded, Decoded)
        time_ns = (decoded.stamp_ns if header_time else 0) or message.time_ns
        for name in (entity, *images):
            run = self.runs.setdefault(name, _Run())
            run.times_ns.append(time_ns)
            run.frames.append(decoded.frame_id)
            run.items.append(decoded.items[0])
            run.nbytes += len(message.data)
            run.pins = run.pins or not _owned(decoded.items[0])
            self.held += len(message.data)
        self.last_ns = time_ns
        runs = [(name, self.runs[name]) for name in (entity, *images) if name in self.runs]
        full = [name for name, run in runs if run.nbytes >= RUN_BYTES or len(run.times_ns) >= RUN_ROWS]
        if self.held >= HELD_BYTES:
            self.send()
        elif full:
            self.send(*full)

    def send(self, *entities: str) -> None:
        """Send the runs of ``entities`` and of the entities below them (every run when none is named)."""
        below = tuple(e + "/" for e in entities)
        for name in [e for e in self.runs if e in entities or e.startswith(below)] if entities else list(self.runs):
            run = self.runs.pop(name)
            self.held -= run.nbytes
            times_ns = np.array(run.times_ns, dtype=np.int64)
            for kind, build in ((shapes.Points, _points), (shapes.Arrows, _arrows), (shapes.Pinhole, _pinholes)):
                rows = [i for i, item in enumerate(run.items) if isinstance(item, kind)]
                if rows:
                    columns = build(name, [run.items[i] for i in rows], [run.frames[i] for i in rows])
                    send(self.rec, name, self.timeline, time_array(times_ns[rows], self.clock), columns)
            for i, item in enumerate(run.items):  # an image a row: its column is a view of its message's bytes
                if isinstance(item, shapes.Image):
                    send(self.rec, name, self.timeline, time_array(times_ns[i : i + 1], self.clock), _image(item))
            encoded_images = [i for i, item in enumerate(run.items) if isinstance(item, shapes.CompressedImage)]
            for media_type in dict.fromkeys(_media(run.items[i]) for i in encoded_images):  # a run of JPEGs: one call
                rows = [i for i in encoded_images if _media(run.items[i]) == media_type]
                columns = _encoded_images([run.items[i] for i in rows])
                send(self.rec, name, self.timeline, time_array(times_ns[rows], self.clock), columns)

    def interrupt(self, *entities: str, everything: bool = False) -> None:
        """Before a message logged on its own (on ``entities``; or at the end of a block: all of them, unless the
        runs are held and not ``everything`` was taken): their runs sent, and the recording's time where the last
        message taken left it (logging it would have set it)."""
        if entities or everything or not self.hold:
            self.send(*entities)
        elif pinning := [name for name, run in self.runs.items() if run.pins]:  # (none named would send them all)
            self.send(*pinning)
        if self.last_ns is not None:
            set_time(self.rec, self.timeline, self.last_ns, self.clock)
            self.last_ns = None


def _owned(item: Shape) -> bool:
    """Whether every array of ``item`` owns its memory (no view of the bytes its message was read in)."""
    if isinstance(item, shapes.Image | shapes.CompressedImage):
        return False
    for f in fields(item):
        array = getattr(item, f.name)
        while isinstance(array, np.ndarray) and isinstance(array.base, np.ndarray):
            array = array.base
        if isinstance(array, np.ndarray) and array.base is not None:
            return False
    return True


def _lists(values: pa.Array, lengths: Sequence[int] | np.ndarray, of: pa.DataType | None = None) -> pa.Array:
    """``values`` cut into consecutive lists of ``lengths`` (one per row; ``of``: the list type, by default of
    nullable items): a component column."""
    offsets = np.zeros(len(lengths) + 1, dtype=np.int32)
    np.cumsum(lengths, out=offsets[1:])
    of = pa.list_(values.type) if of is None else of
    return pa.Array.from_buffers(of, len(lengths), [None, pa.py_buffer(offsets)], children=[values])


def _blob(data: np.ndarray | bytes) -> pa.Array:
    """A row of one blob: a list of its bytes, not copied (Rerun copies them as it writes them)."""
    values = pa.array(np.frombuffer(data, dtype=np.uint8) if isinstance(data, bytes) else data, type=pa.uint8())
    return _lists(_lists(values, [len(values)], _BLOB), _ONE)


def _pixels(image: shapes.Image) -> np.ndarray:
    """The bytes ``rr.Image`` would take (``tobytes``: C order, the dtype's own byte order)."""
    return np.ascontiguousarray(image.pixels).reshape(-1).view(np.uint8)


@cache
def _format(shape: tuple[int, ...], dtype: str, color_model: str) -> pa.Array:
    """The ``ImageFormat`` ``rr.Image`` logs for pixels of this shape and dtype (one row)."""
    image = rr.Image(np.zeros(shape, dtype=np.dtype(dtype)), color_model=color_model)  # type: ignore[arg-type]
    assert image.format is not None
    return image.format.as_arrow_array()


def _image(item: Shape) -> Encoded:
    """The one row of an ``Image`` (buffer, format) or an ``EncodedImage`` (blob, media type)."""
    if isinstance(item, shapes.Image):
        image_format = _format(item.pixels.shape, item.pixels.dtype.str, item.color_model)
        return [
            (rr.Image.descriptor_buffer(), _blob(_pixels(item))),
            (rr.Image.descriptor_format(), _lists(image_format, _ONE)),
        ]
    assert isinstance(item, shapes.CompressedImage)
    return [(rr.EncodedImage.descriptor_blob(), _blob(item.data)), *_media_type(item.media_type)]


def _media(item: Shape) -> str:
    assert isinstance(item, shapes.CompressedImage)
    return item.media_type


def _encoded_images(items: list[Shape]) -> Encoded:
    """A run of ``EncodedImage`` s of one media type, a row each (issue 48: a call and a chunk per JPEG cost more
    than copying their few kB into one column); one alone is :func:`_image`'s row (a view of its bytes)."""
    if len(items) == 1:
        return _image(items[0])
    blobs = [np.frombuffer(i.data, dtype=np.uint8) for i in items if isinstance(i, shapes.CompressedImage)]
    values = pa.array(np.concatenate(blobs), type=pa.uint8())
    column = _lists(_lists(values, [len(b) for b in blobs], _BLOB), np.ones(len(blobs), dtype=np.int64))
    return [(rr.EncodedImage.descriptor_blob(), column), *_media_type(_media(items[0]), len(blobs))]


@lru_cache(maxsize=256)
def _media_type(media_type: str, rows: int = 1) -> Encoded:
    return encoded(rr.EncodedImage.columns(media_type=[media_type] * rows))


def _pinholes(entity: str, items: list[Shape], frames: list[str]) -> Encoded:
    """A run of a camera's pinholes on ``entity``: its image plane's ``CoordinateFrame`` and the ``Pinhole`` from
    the optical frame to it (:func:`r2d2_viz.viewer.displays.image_plane`), a row per message. A camera's model
    rarely changes: a run of one model is built once per model and run length (issue 48: Rerun's converters for
    every run of three entities cost 1.55 s of a 10 s conversion)."""
    pinholes = [i for i in items if isinstance(i, shapes.Pinhole)]
    models = {(_k(p), p.width, p.height, frame) for p, frame in zip(pinholes, frames, strict=True)}
    if len(models) == 1:
        ((k, width, height, frame),) = models
        return list(_same_pinholes(entity, k, width, height, frame, len(pinholes)))
    return _pinhole_columns(entity, pinholes, frames)


def _k(pinhole: shapes.Pinhole) -> bytes:
    return np.asarray(pinhole.K, dtype=np.float64).tobytes()


@lru_cache(maxsize=256)
def _same_pinholes(entity: str, k: bytes, width: int, height: int, frame: str, rows: int) -> tuple[Column, ...]:
    pinhole = shapes.Pinhole(np.frombuffer(k, dtype=np.float64).reshape(3, 3), width, height)
    return tuple(_pinhole_columns(entity, [pinhole] * rows, [frame] * rows))


def _pinhole_columns(entity: str, pinholes: list[shapes.Pinhole], frames: list[str]) -> Encoded:
    planes = [image_plane(entity)] * len(pinholes)
    return [
        *encoded(rr.CoordinateFrame.columns(frame=planes)),
        *encoded(
            rr.Pinhole.columns(
                image_from_camera=np.array([p.K for p in pinholes], dtype=np.float64).reshape(-1, 3, 3),
                resolution=np.array([[p.width, p.height] for p in pinholes], dtype=np.float64).reshape(-1, 2),
                camera_xyz=[rr.ViewCoordinates.RDF] * len(pinholes),
                parent_frame=frames,
                child_frame=planes,
            )
        ),
    ]


def _points(entity: str, items: list[Shape], frames: list[str]) -> Encoded:
    """A run of ``Points`` as columns: ``CoordinateFrame``, ``Points3D`` (positions and colours partitioned per
    message; a radius each) and ``InstancePoses3D`` (one pose each), a row per message. Built as Arrow arrays of
    Rerun's types from numpy (Rerun's ``columns()`` converters cost more than the arrays)."""
    points = [i for i in items if isinstance(i, shapes.Points)]
    ones = np.ones(len(points), dtype=np.int64)
    colors = [packed(p.colors) for p in points]
    positions = np.concatenate([p.positions for p in points]) if points else np.zeros((0, 3), np.float32)
    return [
        (rr.CoordinateFrame.descriptor_frame(), _lists(pa.array(frames, type=pa.utf8()), ones)),
        (rr.Points3D.descriptor_positions(), _lists(_vectors(positions, 3), [len(p.positions) for p in points])),
        (
            rr.Points3D.descriptor_colors(),
            _lists(pa.array(np.concatenate(colors), pa.uint32()), [len(c) for c in colors]),
        ),
        (rr.Points3D.descriptor_radii(), _lists(pa.array(np.array([p.radius for p in points], np.float32)), ones)),
        *_poses([p.T_frame_item for p in points]),
    ]


def _arrows(entity: str, items: list[Shape], frames: list[str]) -> Encoded:
    """A run of ``Arrows`` as columns: ``CoordinateFrame``, ``Arrows3D`` (origins, vectors and colours partitioned per
    message; a radius each) and ``InstancePoses3D`` (one pose each), a row per message."""
    arrows = [i for i in items if isinstance(i, shapes.Arrows)]
    ones = np.ones(len(arrows), dtype=np.int64)
    lengths = [len(a.origins) for a in arrows]
    colors = [packed(a.colors) for a in arrows]
    return [
        (rr.CoordinateFrame.descriptor_frame(), _lists(pa.array(frames, type=pa.utf8()), ones)),
        (rr.Arrows3D.descriptor_vectors(), _lists(_vectors(_stacked([a.vectors for a in arrows]), 3), lengths)),
        (rr.Arrows3D.descriptor_origins(), _lists(_vectors(_stacked([a.origins for a in arrows]), 3), lengths)),
        (rr.Arrows3D.descriptor_radii(), _lists(pa.array(np.array([a.radius for a in arrows], np.float32)), ones)),
        (
            rr.Arrows3D.descriptor_colors(),
            _lists(pa.array(np.concatenate(colors), pa.uint32()), [len(c) for c in colors]),
        ),
        *_poses([a.T_frame_item for a in arrows]),
    ]


def _stacked(parts: list[np.ndarray]) -> np.ndarray:
    return np.concatenate([np.asarray(p, dtype=np.float32).reshape(-1, 3) for p in parts])


def _poses(poses: list[shapes.Pose]) -> Encoded:
    """``InstancePoses3D``: one pose (translation, ``xyzw``) a row."""
    ones = np.ones(len(poses), dtype=np.int64)
    translations = np.array([p.translation for p in poses], dtype=np.float32).reshape(-1, 3)
    quaternions = np.array([p.xyzw for p in poses], dtype=np.float32).reshape(-1, 4)
    return [
        (rr.InstancePoses3D.descriptor_translations(), _lists(_vectors(translations, 3), ones)),
        (rr.InstancePoses3D.descriptor_quaternions(), _lists(_vectors(quaternions, 4), ones)),
    ]


def _vectors(values: np.ndarray, size: int) -> pa.Array:
    """``(n, size)`` float32 rows as Rerun's vectors (a fixed-size list of non-null floats each)."""
    flat = pa.array(np.ascontiguousarray(values, dtype=np.float32).reshape(-1), type=pa.float32())
    return pa.FixedSizeListArray.from_arrays(flat, type=pa.list_(pa.field("item", pa.float32(), nullable=False), size))
