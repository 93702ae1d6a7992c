"""Display data a decoder returns: rerun-free, frozen, numpy arrays in the message's frame.

Colours are RGBA8 arrays ``(N, 4)`` (one per instance) or ``(1, 4)`` (one for all). Quaternions are ``xyzw``.
``T_frame_item`` places a drawing inside the message frame (identity when its coordinates are already there).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

F32 = npt.NDArray[np.float32]
U8 = npt.NDArray[np.uint8]
U32 = npt.NDArray[np.uint32]
Rgba8 = tuple[int, int, int, int]


@dataclass(frozen=True)
class Pose:
    """A rigid transform: ``translation`` (m) and rotation quaternion ``xyzw``."""

    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    xyzw: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)


IDENTITY = Pose()


@dataclass(frozen=True, eq=False)
class Points:
    """Points ``positions (N, 3)`` of one ``radius`` (m)."""

    positions: F32
    colors: U8
    radius: float
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True, eq=False)
class LineStrips:
    """Polylines, each ``(M_i, 3)`` (or all of one length: ``(N, M, 3)``); ``colors`` per strip; ``radius`` of the
    line (m), 0 for a thin line."""

    strips: tuple[F32, ...] | F32
    colors: U8
    radius: float
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True, eq=False)
class Arrows:
    """Arrows from ``origins (N, 3)`` along ``vectors (N, 3)``; ``radius`` of the shaft (m)."""

    origins: F32
    vectors: F32
    colors: U8
    radius: float
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True, eq=False)
class Boxes:
    """Boxes: ``centers``, ``half_sizes`` and ``xyzw`` rotations, each one row per box; optional ``labels`` (one
    per box) and ``edges`` (m: only their edges, that wide; 0: solid)."""

    centers: F32
    half_sizes: F32
    xyzw: F32
    colors: U8
    T_frame_item: Pose = IDENTITY
    labels: tuple[str, ...] = ()
    edges: float = 0.0


@dataclass(frozen=True, eq=False)
class Outlines2D:
    """Closed outlines on an image, in pixels: ``corners (N, 4, 2)`` (each box's four corners in order), one
    colour and label each (vision_msgs' 2D detections); drawn where the image of the same camera is."""

    corners: F32
    colors: U8
    labels: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class Ellipsoids:
    """Ellipsoids (spheres, covariances): ``centers``, ``half_sizes`` and ``xyzw`` rotations, one row each."""

    centers: F32
    half_sizes: F32
    xyzw: F32
    colors: U8
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True, eq=False)
class Cylinders:
    """Cylinders along their local z: ``centers``, ``lengths``, ``radii``, ``xyzw`` rotations."""

    centers: F32
    lengths: F32
    radii: F32
    xyzw: F32
    colors: U8
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True, eq=False)
class TriangleMesh:
    """Triangles ``indices (M, 3)`` into ``vertices (N, 3)``; ``colors`` per vertex ``(N, 4)`` or ``(1, 4)``."""

    vertices: F32
    indices: U32
    colors: U8
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True)
class Text:
    """A label facing the viewer at ``position``, ``height`` m tall."""

    text: str
    position: tuple[float, float, float]
    height: float
    color: Rgba8
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True)
class MeshResource:
    """A mesh file by ``uri`` (``package://``, ``file://``), resolved elsewhere; ``color`` None keeps its own."""

    uri: str
    scale: tuple[float, float, float]
    color: Rgba8 | None
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True, eq=False)
class Image:
    """A raw image: ``pixels`` ``(H, W)`` or ``(H, W, C)``, ``color_model`` L / RGB / RGBA / BGR / BGRA."""

    pixels: npt.NDArray[np.generic]
    color_model: Literal["L", "RGB", "RGBA", "BGR", "BGRA"]
    encoding: str


@dataclass(frozen=True)
class CompressedImage:
    """An encoded image: the file bytes and their media type (``image/jpeg``, ``image/png``)."""

    data: bytes
    media_type: str


@dataclass(frozen=True)
class VideoSample:
    """One frame of a video stream (Rerun's ``VideoStream`` sample): ``codec`` AV1 / H264 / H265 / VP9, its bytes
    (Annex B for H.264/H.265, low-overhead OBUs for AV1), and whether a decoder can start there."""

    codec: Literal["AV1", "H264", "H265", "VP9"]
    data: bytes
    keyframe: bool


@dataclass(frozen=True, eq=False)
class Pinhole:
    """A camera model: intrinsics ``K`` (3x3, pixels) and image size; the frame is the optical frame (RDF)."""

    K: npt.NDArray[np.float64]
    width: int
    height: int


@dataclass(frozen=True, eq=False)
class GridMap:
    """A coloured grid: ``rgba (H, W, 4)`` where row 0 is y = 0, cells ``resolution`` m; ``T_frame_item`` is
    the pose of cell (0, 0)'s corner."""

    rgba: U8
    resolution: float
    T_frame_item: Pose = IDENTITY


@dataclass(frozen=True)
class LogLine:
    """A line of a log (``/rosout``, a ``String`` topic): ``level`` in Rerun's names (DEBUG, INFO, WARN, ERROR,
    CRITICAL; "" for none)."""

    level: str
    text: str


@dataclass(frozen=True)
class Status:
    """One diagnostic status: its name as entity path parts (``/Robot/Motors`` → Robot, Motors), its level (OK,
    WARN, ERROR, STALE), message, hardware id, key/values as the message gives them (text), and its ``name``."""

    parts: tuple[str, ...]
    level: str
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...]
    name: str = ""


@dataclass(frozen=True)
class Statuses:
    """A DiagnosticArray's statuses, each on its own entity below the topic's."""

    items: tuple[Status, ...]


@dataclass(frozen=True, eq=False)
class Series:
    """Numbers to plot (one sample of each): on ``<topic>/<name>`` (the topic's own entity when ``name`` is "")
    with one series per ``labels`` entry; NaN is a gap."""

    name: str
    labels: tuple[str, ...]
    values: npt.NDArray[np.float64]


@dataclass(frozen=True)
class GeoPoint:
    """A position on the Earth (WGS 84 degrees), for a map."""

    latitude: float
    longitude: float


Plain = LogLine | Statuses | Series | GeoPoint
"""What is not drawn in 3D (a log, states, plots, a map): logged on entities of its own, in no TF frame."""


Shape = (
    Points
    | LineStrips
    | Arrows
    | Boxes
    | Ellipsoids
    | Cylinders
    | TriangleMesh
    | Text
    | MeshResource
    | Outlines2D
    | Image
    | CompressedImage
    | VideoSample
    | Pinhole
    | GridMap
    | Plain
)


def is_plain(item: Shape) -> bool:
    """Whether ``item`` is not drawn in 3D (:data:`Plain`)."""
    return isinstance(item, (LogLine, Statuses, Series, GeoPoint))


@dataclass(frozen=True)
class Decoded:
    """One message's drawings in ``frame_id`` (no leading '/') at header time ``stamp_ns``."""

    frame_id: str
    stamp_ns: int
    items: tuple[Shape, ...] = field(default_factory=tuple)


@dataclass(frozen=True)
class MarkerOp:
    """One Marker's effect, keyed by ``(ns, id)``: ``add`` (ADD / MODIFY) draws ``decoded``, kept ``lifetime_ns``
    (0 = forever); ``delete`` removes the key; ``deleteall`` removes every marker (of ``ns`` when it is set)."""

    action: Literal["add", "delete", "deleteall"]
    ns: str
    id: int
    decoded: Decoded | None = None
    lifetime_ns: int = 0
    frame_locked: bool = False


@dataclass(frozen=True)
class DecodeOptions:
    """Display settings RViz offers per display (its defaults)."""

    map_scheme: Literal["map", "costmap", "raw"] = "map"
    point_radius: float = 0.005  # RViz's Size (m) 0.01 is a diameter
    flat_color: Rgba8 = (255, 255, 255, 255)
    covariance_scale: float = 1.0  # half sizes = scale x sqrt(eigenvalue): 1 sigma, RViz's default
    color_transformer: Literal["auto", "FlatColor"] = "auto"  # auto: RGB8, else Intensity, else flat (RViz's)
    odometry_covariance: bool = False  # an Odometry's covariance ellipsoid (off unless a config asks for it)
    # nav2's ParticleCloud and vision_msgs' Detection3DArray displays (their properties, their defaults)
    display_color: Rgba8 | None = None  # a config's Color and Alpha (None: the display's own colour)
    particle_shape: Literal["Arrow (Flat)", "Arrow (3D)", "Axes"] = "Arrow (Flat)"
    arrow_lengths: tuple[float, float] = (0.02, 0.3)  # Min / Max Arrow Length (m): weight 0 → min, 1 → max
    only_edge: bool = False  # Detection3DArray: edges of the boxes only, Line Width wide
    line_width: float = 0.05
    alpha: float = 1.0
    value_range: tuple[float, float] | None = None  # a scalar point display's Min/Max Intensity (None: RViz's)
    depth_cloud: tuple[str, str] | None = None  # DepthCloud: (its CameraInfo topic, its Color Image Topic or "")
    effort: tuple[Any, ...] = ()  # Effort: the robot's revolute joints (r2d2_viz.msgs.rviz2.effort.EffortJoint)
    effort_size: tuple[float, float] = (0.02, 1.0)  # Effort's Width (m) and Scale
