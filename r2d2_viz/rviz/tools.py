"""RViz's tools that talk back to the robot: their names as RViz's toolbar shows them, the message each sends, its
default topic, and the topics an RViz config's ``Tools`` section gives them. Pure: no rerun.

RViz 2 saves a tool's topic as ``Topic: {Value: /goal_pose, Depth: 5, …}``; RViz 1 as ``Topic: /move_base_simple/goal``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from r2d2_viz.errors import UsageError

POSE_ESTIMATE = "2D Pose Estimate"
GOAL_POSE = "2D Goal Pose"
PUBLISH_POINT = "Publish Point"
MEASURE = "Measure"
TELEOP = "Teleop"
TOOLS = (POSE_ESTIMATE, GOAL_POSE, PUBLISH_POINT, MEASURE, TELEOP)
"""The page's toolbar, in RViz's order (Teleop is rviz_teleop's pad, not a default tool)."""

MESSAGE_TYPES = {
    POSE_ESTIMATE: "geometry_msgs/msg/PoseWithCovarianceStamped",
    GOAL_POSE: "geometry_msgs/msg/PoseStamped",
    PUBLISH_POINT: "geometry_msgs/msg/PointStamped",
    TELEOP: "geometry_msgs/msg/Twist",
}
DEFAULT_TOPICS = {
    POSE_ESTIMATE: "/initialpose",
    GOAL_POSE: "/goal_pose",
    PUBLISH_POINT: "/clicked_point",
    TELEOP: "/cmd_vel",
}
"""RViz 2's defaults (rviz_default_plugins), and teleop_twist_keyboard's."""

RVIZ_CLASSES = {"SetInitialPose": POSE_ESTIMATE, "SetGoal": GOAL_POSE, "PublishPoint": PUBLISH_POINT}
"""RViz's tool classes (``rviz_default_plugins/SetGoal``, ``rviz/SetGoal``) → the page's tools."""

ALIASES = {
    "pose_estimate": POSE_ESTIMATE,
    "initialpose": POSE_ESTIMATE,
    "goal": GOAL_POSE,
    "goal_pose": GOAL_POSE,
    "point": PUBLISH_POINT,
    "clicked_point": PUBLISH_POINT,
    "teleop": TELEOP,
    "cmd_vel": TELEOP,
}
"""Short names for ``--tool-topic NAME=TOPIC`` (the full names, any case, work too)."""


def tool_name(name: str) -> str | None:
    """``goal``, ``2D Goal Pose`` or ``SetGoal`` → ``2D Goal Pose``; None for a tool that sends nothing."""
    key = name.strip()
    for tool in MESSAGE_TYPES:
        if key.lower() == tool.lower():
            return tool
    return ALIASES.get(key.lower().replace("-", "_").replace(" ", "_")) or RVIZ_CLASSES.get(key.rsplit("/", 1)[-1])


def config_tool_topics(tools: Any) -> dict[str, str]:
    """The topics an RViz config's ``Tools`` list gives the tools that publish (those it names)."""
    found: dict[str, str] = {}
    for item in tools if isinstance(tools, list) else []:
        if not isinstance(item, Mapping):
            continue
        tool = RVIZ_CLASSES.get(str(item.get("Class", "")).rsplit("/", 1)[-1])
        topic = item.get("Topic")
        if isinstance(topic, Mapping):  # RViz 2
            topic = topic.get("Value")
        if tool is not None and isinstance(topic, str) and topic.strip():
            found[tool] = topic.strip()
    return found


def tool_topics(config: Mapping[str, str] | None = None, overrides: Mapping[str, str] | None = None) -> dict[str, str]:
    """Each publishing tool's topic: RViz's default, else the config's, else ``overrides``'s (``--tool-topic``)."""
    return {**DEFAULT_TOPICS, **(config or {}), **(overrides or {})}


def parse_tool_topics(items: list[str]) -> tuple[tuple[str, str], ...]:
    """``--tool-topic goal=/move_base_simple/goal`` → ``(("2D Goal Pose", "/move_base_simple/goal"),)``."""
    found: dict[str, str] = {}
    for item in items:
        name, sep, topic = item.partition("=")
        tool = tool_name(name)
        if not sep or tool is None:
            raise UsageError(
                f"--tool-topic {item!r}: expected TOOL=TOPIC, TOOL one of goal, pose_estimate, point, teleop"
            )
        topic = topic.strip()
        if not topic.startswith("/") or not all(part.isidentifier() for part in topic[1:].split("/")):
            raise UsageError(f"--tool-topic {item!r}: {topic!r} is not a ROS topic name (such as /goal_pose)")
        found[tool] = topic
    return tuple(found.items())
