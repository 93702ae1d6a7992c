"""Names in the recording: the application id, the timeline, and the entity paths every part logs to.

Every name that comes from a URDF (links, joints) is escaped for entity paths (spaces, slashes, non-ASCII).
"""

from __future__ import annotations

import rerun as rr

APP_ID = "r2d2_viz"
TIMELINE = "time"
"""Generated motions: a duration since the start; bags: a timestamp (see :data:`r2d2_viz.sources.base.Clock`)."""


def path(*parts: str) -> str:
    """An entity path from unescaped parts (link names may hold spaces, slashes, non-ASCII)."""
    return "/" + "/".join(rr.escape_entity_path_part(p) for p in parts)


TF = "/tf"
"""Every moving transform, one row per joint per sample (like the /tf topic); the moving TF arrows ride along."""
WARNINGS = "/warnings"
JOINTS_LIMITED = "/joints/limited"
JOINTS_CONTINUOUS = "/joints/continuous"
LIMITS = "/joints/limited/limits"


def tf_static(child: str) -> str:
    return path("tf_static", child)


def tf_axes(frame: str) -> str:
    return path("tf_axes", frame)


def tf_arrow(child: str) -> str:
    return path("tf_arrows", child)


def robot_root(robot: str = "") -> str:
    """Where a robot's shapes go: ``/robot`` (one robot, or the root namespace's), ``/robots/<namespace>`` (each
    namespaced robot when a run shows several)."""
    return path("robots", *robot.strip("/").split("/")) if robot.strip("/") else "/robot"


def robot_shape(kind: str, link: str, index: int, robot: str = "") -> str:
    """``kind``: ``visual`` or ``collision``; ``robot``: the robot's namespace when a run shows several."""
    return robot_root(robot) + path(kind, link, str(index))


def joints_root(robot: str = "") -> str:
    """Where a robot's joint plots go: ``/joints`` (one robot), ``/joints/<namespace>`` (several)."""
    return path("joints", *robot.strip("/").split("/")) if robot.strip("/") else "/joints"
