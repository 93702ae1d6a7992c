"""The decode options of the RViz displays added for issue 46 (:mod:`r2d2_viz.msgs.rviz2.joined`,
:mod:`r2d2_viz.msgs.rviz2.scalar_points`): a scalar display's Min/Max Intensity, DepthCloud's camera info and colour
topics, Effort's joints (the robot's revolute joints: RViz's Effort display draws no other), Width and Scale."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from r2d2_viz.msgs.rviz2.effort import SCALE, WIDTH, EffortJoint
from r2d2_viz.msgs.rviz2.joined import info_topic
from r2d2_viz.robot.model import Robot
from r2d2_viz.rviz.config import load_rviz
from r2d2_viz.rviz.spec import TopicDisplay


def effort_joints(robot: Robot) -> tuple[EffortJoint, ...]:
    """The robot's revolute joints as the Effort display reads them (no ``<limit effort>``: 0, no limit)."""
    return tuple(
        EffortJoint(j.name, j.child, j.axis, float(j.limit.effort or 0.0) if j.limit is not None else 0.0)
        for j in robot.joints
        if j.type == "revolute"
    )


def joined_options(display: TopicDisplay, robot: Robot | None) -> dict[str, Any]:
    """``DecodeOptions`` fields for ``display`` (empty for the other displays)."""
    s = display.style
    out: dict[str, Any] = {}
    if s.value_range is not None:
        out["value_range"] = s.value_range
    if display.kind == "DepthCloud" and display.topic:
        out["depth_cloud"] = (info_topic(display.topic), s.color_topic or "")
    if display.kind == "Effort" and robot is not None:
        out["effort"] = effort_joints(robot)
        out["effort_size"] = (s.width if s.width is not None else WIDTH, s.scale if s.scale is not None else SCALE)
    return out


def joined_topics(rviz: Path | None) -> tuple[str, ...]:
    """The topics an RViz config's enabled Effort displays read (a JointState topic: read as a display topic too,
    ``/joint_states`` included)."""
    if rviz is None:
        return ()
    return tuple(t.topic for t in load_rviz(rviz).topics if t.kind == "Effort" and t.enabled and t.topic)
