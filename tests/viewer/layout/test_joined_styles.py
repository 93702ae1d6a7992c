"""The decode options of DepthCloud, Effort and the scalar displays, from a config and a URDF."""

from __future__ import annotations

from pathlib import Path

from r2d2_viz.msgs.rviz2.effort import EffortJoint
from r2d2_viz.robot.model import parse_urdf
from r2d2_viz.rviz.config import parse_rviz
from r2d2_viz.viewer.layout.joined_styles import effort_joints, joined_options, joined_topics

URDF = """<robot name="r"><link name="a"/><link name="b"/><link name="c"/><link name="d"/>
<joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/>
  <limit lower="-1" upper="1" effort="7" velocity="1"/></joint>
<joint name="j2" type="continuous"><parent link="b"/><child link="c"/></joint>
<joint name="j3" type="prismatic"><parent link="c"/><child link="d"/>
  <limit lower="0" upper="1" effort="3" velocity="1"/></joint>
</robot>"""

CONFIG = """Visualization Manager:
  Displays:
    - Class: rviz_default_plugins/DepthCloud
      Name: depth
      Depth Map Topic: /cam/depth/image_rect_raw
      Color Image Topic: /cam/color/image_raw
    - Class: rviz_default_plugins/Effort
      Name: effort
      Topic: {Value: /arm/joint_states}
      Width: 0.05
    - Class: rviz_default_plugins/Effort
      Enabled: false
      Name: off
      Topic: {Value: /off/joint_states}
    - Class: rviz_default_plugins/FluidPressure
      Name: p
      Topic: {Value: /p}
      Min Intensity: 90000
      Max Intensity: 110000
"""


def test_only_revolute_joints_with_their_effort_limit() -> None:
    robot = parse_urdf(URDF, source="r.urdf")
    assert effort_joints(robot) == (EffortJoint("j1", "b", (0.0, 1.0, 0.0), 7.0),)


def test_options_of_each_display(tmp_path: Path) -> None:
    spec = parse_rviz(CONFIG, source="c.rviz")
    depth, effort, _, pressure = spec.topics
    robot = parse_urdf(URDF, source="r.urdf")
    assert joined_options(depth, robot) == {"depth_cloud": ("/cam/depth/camera_info", "/cam/color/image_raw")}
    assert joined_options(effort, robot)["effort_size"] == (0.05, 1.0)  # Width set, Scale RViz's 1
    assert joined_options(effort, None) == {}  # no robot: nothing to draw at
    assert joined_options(pressure, robot) == {"value_range": (90000.0, 110000.0)}
    path = tmp_path / "c.rviz"
    path.write_text(CONFIG)
    assert joined_topics(path) == ("/arm/joint_states",) and joined_topics(None) == ()
