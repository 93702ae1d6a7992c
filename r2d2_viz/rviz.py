"""RViz configs (``.rviz``, ROS 1 and ROS 2) → a :class:`ViewSpec`: what the Rerun layout needs to look like it.

Read with a YAML safe loader (no tags, no objects; size-limited). Every display, tool and panel class with no
counterpart is named once in :attr:`ViewSpec.notes`. Camera formulas are RViz's own (rviz_default_plugins'
view controllers, ROS 2; rviz's ``default_plugin/view_controllers``, ROS 1 — the same maths):

- Orbit (``OrbitViewController::updateCamera``): the eye at ``focal + distance · (cos yaw cos pitch,
  sin yaw cos pitch, sin pitch)`` looking at the focal point, up +Z; with Invert Z Axis, yaw and pitch are
  negated and up is −Z.
- XYOrbit and ThirdPersonFollower (``XYOrbitViewController::updateCamera``; ROS 1's follower does the same):
  the Orbit camera lifted by ``0.2 · distance`` along its own up vector ``(−sin pitch cos yaw, −sin pitch sin yaw,
  cos pitch)``, so the focal point sits in the lower half of the image; the view direction is unchanged.
- FPS (``FPSViewController::getOrientation``: yaw about Z · pitch about Y · roll about X): from Position,
  looking along ``(cos pitch cos yaw, cos pitch sin yaw, −sin pitch)``.
- TopDownOrtho (``FixedOrientationOrthoViewController``): straight down at (X, Y), the image turned by Angle,
  ``Scale`` pixels a metre.

Pure: no rerun.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .errors import R2d2VizError

MAX_BYTES = 4 * 1024 * 1024
FIXED = "<Fixed Frame>"
FOV_Y = math.radians(45.0)
XY_ORBIT_LIFT = 0.2
"""RViz's XYOrbit / ThirdPersonFollower ``CAMERA_OFFSET``: the eye is lifted by this times the distance."""
ASSUMED_VIEW_HEIGHT_PX = 800
"""TopDownOrtho's Scale is pixels a metre; Rerun has no orthographic 3D camera, so the eye stands as high as
shows this many pixels' worth of metres (an RViz window's 3D view is about this tall)."""
TOPIC_DISPLAYS = (
    "LaserScan",
    "PointCloud2",
    "PointCloud",
    "Marker",
    "MarkerArray",
    "Path",
    "Odometry",
    "Pose",
    "PoseArray",
    "Map",
    "Image",
    "Camera",
    "Range",
    "Polygon",
    "PointStamped",
)
UNSHOWN_BY_RERUN = ("LaserScan", "Marker", "MarkerArray", "Path", "Odometry", "Map", "Range", "Polygon", "PoseArray")
"""Topic displays whose messages Rerun 0.41's MCAP decoders cannot draw (the entity is still mapped)."""


SCENE_ROBOT_DISPLAYS = ("MotionPlanning", "PlanningScene")
"""MoveIt's displays (``moveit_rviz_plugin/…``) that draw the robot as their "Scene Robot"."""


class RvizError(R2d2VizError):
    """An .rviz file that cannot be read; the message names the file and the key."""


@dataclass(frozen=True)
class Camera:
    kind: str
    """The RViz view controller class, short (``Orbit``, ``XYOrbit``, ``TopDownOrtho``, ``FPS``, …)."""
    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    orbit: bool = True
    """Rerun's orbital eye (else first person)."""
    orthographic: bool = False
    """RViz drew it with an orthographic projection (TopDownOrtho); Rerun's 3D view is perspective."""
    target_frame: str | None = None
    """A frame the camera follows (RViz's Target Frame, when not the fixed frame)."""


@dataclass(frozen=True)
class Grid:
    enabled: bool = True
    cell_size: float = 1.0
    color: tuple[int, int, int] = (160, 160, 164)
    alpha: float = 0.5
    plane: str = "XY"
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    reference_frame: str | None = None
    """None: the fixed frame."""


@dataclass(frozen=True)
class Tf:
    enabled: bool = True
    show_axes: bool = True
    show_arrows: bool = True
    show_names: bool = False
    marker_scale: float = 1.0
    hidden_frames: tuple[str, ...] = ()


@dataclass(frozen=True)
class RobotModel:
    enabled: bool = True
    visual: bool = True
    collision: bool = False
    alpha: float = 1.0
    hidden_links: tuple[str, ...] = ()


@dataclass(frozen=True)
class TopicDisplay:
    kind: str
    name: str
    topic: str
    enabled: bool


@dataclass(frozen=True)
class ViewSpec:
    source: str
    fixed_frame: str = "odom"
    background: tuple[int, int, int] = (48, 48, 48)
    grid: Grid | None = field(default_factory=Grid)
    tf: Tf | None = field(default_factory=Tf)
    robot: RobotModel | None = field(default_factory=RobotModel)
    camera: Camera | None = None
    topics: tuple[TopicDisplay, ...] = ()
    notes: tuple[str, ...] = ()
    """One line per thing with no counterpart in Rerun, naming it."""


def default_rviz_path() -> Path:
    """The tutorial's r2d2.rviz, shipped as package data beside the URDF."""
    from .model import asset_path

    return asset_path("r2d2.rviz")


def load_rviz(path: str | Path) -> ViewSpec:
    path = Path(path)
    name = path.name or str(path)
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise RvizError(f"{name}: file is too large ({size} bytes; the limit is {MAX_BYTES})")
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise RvizError(f"{name}: file not found ({path})") from None
    except IsADirectoryError:
        raise RvizError(f"{name}: is a directory, not an .rviz file") from None
    except UnicodeDecodeError as exc:
        raise RvizError(f"{name}: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise RvizError(f"{name}: cannot read: {exc.strerror}") from None
    return parse_rviz(text, source=name)


_SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
"""libyaml's safe loader (~10x faster: 3 ms for r2d2.rviz against 29 ms), pure Python's where PyYAML lacks it."""


def parse_rviz(text: str, *, source: str = "config.rviz") -> ViewSpec:
    try:
        data = yaml.load(text, Loader=_SAFE_LOADER)  # a safe loader (no tags, no objects)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}: " if mark is not None else ""
        raise RvizError(f"{source}: {where}not YAML: {getattr(exc, 'problem', None) or exc}") from None
    if not isinstance(data, dict):
        raise RvizError(f"{source}: not an RViz config (expected a mapping with 'Visualization Manager')")
    manager = data.get("Visualization Manager")
    if not isinstance(manager, dict):
        raise RvizError(f"{source}: no 'Visualization Manager' mapping; is this an RViz config?")
    from .rviz_read import Reader

    return Reader(source).spec(data, manager)


def orbit_eye(
    focal: tuple[float, float, float], distance: float, yaw: float, pitch: float
) -> tuple[float, float, float]:
    """RViz's Orbit view (rviz_default_plugins, ``OrbitViewController::calculatePositionFromYawAndPitch``)."""
    fx, fy, fz = focal
    return (
        fx + distance * math.cos(yaw) * math.cos(pitch),
        fy + distance * math.sin(yaw) * math.cos(pitch),
        fz + distance * math.sin(pitch),
    )


def orbit_view(
    focal: tuple[float, float, float],
    distance: float,
    yaw: float,
    pitch: float,
    *,
    invert_z: bool = False,
    lift: float = 0.0,
) -> tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]:
    """(eye, look target, up) of RViz's Orbit view, lifted by ``lift · distance`` along the camera's own up
    (``lift`` = :data:`XY_ORBIT_LIFT` for XYOrbit and ThirdPersonFollower). See the module's docstring."""
    sign = -1.0 if invert_z else 1.0
    yaw, pitch = sign * yaw, sign * pitch
    eye = orbit_eye(focal, distance, yaw, pitch)
    # the camera's up: world ±Z made perpendicular to the view direction (Ogre's fixed yaw axis)
    cam_up = (
        -sign * math.sin(pitch) * math.cos(yaw),
        -sign * math.sin(pitch) * math.sin(yaw),
        sign * math.cos(pitch),
    )
    shift = tuple(lift * distance * u for u in cam_up)
    eye = (eye[0] + shift[0], eye[1] + shift[1], eye[2] + shift[2])
    target = (focal[0] + shift[0], focal[1] + shift[1], focal[2] + shift[2])
    return eye, target, (0.0, 0.0, sign)


def missing_fixed_frame(spec: ViewSpec, frames: Iterable[str]) -> str | None:
    """RViz's words when the fixed frame is not among the frames a run has."""
    if spec.fixed_frame in set(frames):
        return None
    return f"{spec.source}: Fixed Frame [{spec.fixed_frame}] does not exist; the view opens on it all the same"


missing_fixed_frame_warning = missing_fixed_frame


def short_class(cls: Any) -> str:
    """``rviz_default_plugins/Grid``, ``rviz/Grid`` → ``Grid``."""
    return str(cls).rsplit("/", 1)[-1] if cls else ""
