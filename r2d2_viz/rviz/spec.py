"""What an RViz config says, as data (:class:`ViewSpec`), and RViz's camera maths.

Every display, tool and panel class with no counterpart is named once in :attr:`ViewSpec.notes`. Camera formulas
are RViz's own (rviz_default_plugins' view controllers, ROS 2; rviz's ``default_plugin/view_controllers``, ROS 1
— the same maths):

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
from typing import Any

from r2d2_viz.errors import R2d2VizError

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
    "PoseWithCovariance",
    "GridCells",
    "Wrench",
    "Twist",
    # the navigation and perception stacks' (nav2_rviz_plugins/ParticleCloud, vision_msgs_rviz_plugins/…)
    "ParticleCloud",
    "Detection3DArray",
    # issue 46: RViz 2's classes (rviz_default_plugins/plugins_description.xml) drawn since
    "TwistStamped",
    "AccelStamped",
    "CameraInfo",
    "Temperature",
    "FluidPressure",
    "Illuminance",
    "RelativeHumidity",
    "DepthCloud",
    "Effort",
    "InteractiveMarkers",
)
TOPIC_KEYS = ("Topic", "Image Topic", "Depth Map Topic", "Interactive Markers Namespace", "Update Topic")
"""Where a display names its topic: most say ``Topic``; Camera ``Image Topic``; DepthCloud ``Depth Map Topic``;
InteractiveMarkers ``Interactive Markers Namespace`` (ROS 2: ``<namespace>/update``) or ``Update Topic`` (ROS 1)."""

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
    description_topic: str = "/robot_description"
    """Which robot it draws (several robots: ``/robot2/robot_description``)."""
    tf_prefix: str = ""
    """The prefix of the robot's frames (robot_state_publisher's ``frame_prefix``), ``robot1`` or ``""``."""
    mass: bool = False
    """``Mass Properties / Mass``: each link's centre of mass, a ball of lead of its mass (``--mass``)."""
    inertia: bool = False
    """``Mass Properties / Inertia``: each link's box of equal inertia (``--inertia``)."""
    axes: tuple[str, ...] = ()
    """The links whose ``Links / <link> / Show Axes`` is on (``--link-axes``: every link, ``("*",)``)."""


@dataclass(frozen=True)
class DisplayStyleSpec:
    """What a topic display's properties say about how it draws (None: the display's default)."""

    color: tuple[int, int, int] | None = None
    alpha: float | None = None
    size: float | None = None
    """``Size (m)`` of points, or a line width."""
    color_transformer: str | None = None
    decay_time: float | None = None
    keep: int | None = None
    color_scheme: str | None = None
    covariance: bool | None = None
    position_tolerance: float | None = None
    """Odometry's Position Tolerance (m) and Angle Tolerance (rad)."""
    angle_tolerance: float | None = None
    # nav2's ParticleCloud: Shape, Min / Max Arrow Length; vision_msgs' Detection3DArray: Only Edge
    shape: str | None = None
    arrow_lengths: tuple[float | None, float | None] = (None, None)
    only_edge: bool | None = None
    length: float | None = None
    """Axes' Length (m); CameraInfo's Far clip (m)."""
    radius: float | None = None
    """Axes' Radius (m)."""
    scale: float | None = None
    """Effort's Scale."""
    width: float | None = None
    """Effort's Width (m)."""
    value_range: tuple[float, float] | None = None
    """The scalar point displays' Min and Max Intensity (RViz's defaults per type when unset)."""
    color_topic: str | None = None
    """DepthCloud's Color Image Topic."""
    frame: str | None = None
    """Axes' Reference Frame (None: the fixed frame)."""


@dataclass(frozen=True)
class TopicDisplay:
    kind: str
    name: str
    topic: str
    enabled: bool
    style: DisplayStyleSpec = field(default_factory=DisplayStyleSpec)


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
    more_robots: tuple[RobotModel, ...] = ()
    """The config's other RobotModel displays (several robots, each its own Description Topic)."""
    tool_topics: tuple[tuple[str, str], ...] = ()
    """The topics the config's Tools section gives RViz's publishing tools (``2D Goal Pose`` → ``/goal_pose``)."""


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
