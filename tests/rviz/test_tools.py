"""RViz's publishing tools: names, default topics, and the topics a config's Tools section gives them."""

from __future__ import annotations

import yaml

from r2d2_viz.robot.model import asset_path
from r2d2_viz.rviz.config import load_rviz, parse_rviz
from r2d2_viz.rviz.tools import DEFAULT_TOPICS, config_tool_topics, tool_name, tool_topics

ROS1 = """
Visualization Manager:
  Global Options: {Fixed Frame: map}
  Tools:
    - Class: rviz/SetInitialPose
      Topic: /initialpose
    - Class: rviz/SetGoal
      Topic: /move_base_simple/goal
    - Class: rviz/PublishPoint
      Single click: true
      Topic: /clicked_point
    - Class: rviz/Measure
"""


def test_names() -> None:
    assert tool_name("goal") == tool_name("2D goal pose") == tool_name("rviz_default_plugins/SetGoal") == "2D Goal Pose"
    assert tool_name("point") == tool_name("clicked_point") == "Publish Point"
    assert tool_name("pose-estimate") == "2D Pose Estimate" and tool_name("cmd_vel") == "Teleop"
    assert tool_name("Measure") is None and tool_name("nothing") is None  # Measure publishes nothing


def test_the_tutorial_config_names_rviz_defaults() -> None:
    # the topics written in assets/r2d2.rviz's Tools section (read here with PyYAML, not the code under test)
    tools = yaml.safe_load(asset_path("r2d2.rviz").read_text())["Visualization Manager"]["Tools"]
    written = {t["Class"].split("/")[-1]: t["Topic"]["Value"] for t in tools if "Topic" in t}
    assert written == {"SetInitialPose": "/initialpose", "SetGoal": "/goal_pose", "PublishPoint": "/clicked_point"}
    spec = load_rviz(asset_path("r2d2.rviz"))
    assert dict(spec.tool_topics) == {"2D Pose Estimate": "/initialpose", "2D Goal Pose": "/goal_pose",
                                      "Publish Point": "/clicked_point"}  # fmt: skip


def test_ros1_configs_and_overrides() -> None:
    config = dict(parse_rviz(ROS1).tool_topics)
    assert config["2D Goal Pose"] == "/move_base_simple/goal"
    topics = tool_topics(config, {"Teleop": "/robot/cmd_vel"})
    assert topics == {**DEFAULT_TOPICS, "2D Goal Pose": "/move_base_simple/goal", "Teleop": "/robot/cmd_vel"}
    assert config_tool_topics("not a list") == {} and config_tool_topics([{"Class": "rviz/SetGoal", "Topic": 3}]) == {}
