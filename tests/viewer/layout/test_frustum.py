"""RViz's CameraInfo display as the pinhole's frustum override (camera_info_display.cpp: Far clip 1, Color
(85, 255, 255), Alpha 0.5)."""

from __future__ import annotations

from r2d2_viz.rviz.config import parse_rviz
from r2d2_viz.viewer.layout.frustum import frustums

CONFIG = """Visualization Manager:
  Displays:
    - Class: rviz_default_plugins/CameraInfo
      Enabled: true
      Name: defaults
      Topic: {Value: /cam/camera_info}
    - Class: rviz_default_plugins/CameraInfo
      Enabled: true
      Name: set
      Topic: {Value: /arm_cam/camera_info}
      Far clip: 3.5
      Color: 255; 0; 0
      Alpha: 1
    - Class: rviz_default_plugins/CameraInfo
      Enabled: false
      Name: off
      Topic: {Value: /off/camera_info}
"""


def _fields(pinhole: object) -> tuple[float, int]:
    distance = pinhole.image_plane_distance.as_arrow_array().to_pylist()[0]  # type: ignore[attr-defined]
    color = pinhole.color.as_arrow_array().to_pylist()[0]  # type: ignore[attr-defined]
    return distance, color


def test_far_clip_colour_and_alpha_and_disabled_displays() -> None:
    out = frustums(parse_rviz(CONFIG, source="c.rviz"))
    assert sorted(out) == ["/arm_cam/camera_info", "/cam/camera_info"]
    assert _fields(out["/cam/camera_info"]) == (1.0, 0x55FFFF80)
    assert _fields(out["/arm_cam/camera_info"]) == (3.5, 0xFF0000FF)
