"""One bag's episode parts: values against rosbags' reading of the bag (lerobotbags.expected)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from lerobotbags import JOINTS_URDF_ORDER, URDF, expected, write_arm_bag

from r2d2_viz.errors import BagError
from r2d2_viz.export.lerobot_episode import EpisodeSpec, camera_key, export_episode, urdf_joint_order


def test_state_action_and_camera_of_a_twist_bag(tmp_path: Path) -> None:
    bag = write_arm_bag(tmp_path / "bag", command="twist", seconds=1.0)
    (tmp_path / "out").mkdir()
    part = export_episode(EpisodeSpec(bag.path, tmp_path / "out", fps=20, action="/cmd_vel", codec="h264"))
    want = expected(bag, 20)
    assert part.frames == len(want["frames_ns"]) and part.start_ns == want["frames_ns"][0]
    assert part.state_names == JOINTS_URDF_ORDER and np.array_equal(part.state, want["state"])
    assert part.action_names[0] == "linear.x" and np.array_equal(part.action, want["action"])
    assert part.cameras == {"observation.images.camera_image_raw": (240, 320)}
    assert (tmp_path / "out" / "observation.images.camera_image_raw.mp4").stat().st_size > 0
    assert part.robot_type == "two_joint_arm"


def test_without_action_or_camera(tmp_path: Path) -> None:
    bag = write_arm_bag(tmp_path / "bag", camera=False, seconds=0.5)
    part = export_episode(EpisodeSpec(bag.path, tmp_path, fps=10))
    assert (
        part.action is None and part.cameras == {} and part.frames == 6
    )  # joint states 0 .. 0.5 s: frames at 0, 0.1 .. 0.5 s


def test_bad_bags_are_one_line_naming_bag_and_topic(tmp_path: Path) -> None:
    nothing = write_arm_bag(tmp_path / "nothing", joints=False, camera=False)
    with pytest.raises(BagError, match="no /joint_states and no camera topic"):
        export_episode(EpisodeSpec(nothing.path, tmp_path))
    arm = write_arm_bag(tmp_path / "arm", seconds=0.5)
    with pytest.raises(BagError, match=r"arm: no topic /cmd_vel \(--action\)"):
        export_episode(EpisodeSpec(arm.path, tmp_path, action="/cmd_vel"))
    with pytest.raises(BagError, match=r"--action /robot_description is std_msgs/msg/String, not a command"):
        export_episode(EpisodeSpec(arm.path, tmp_path, action="/robot_description"))


def test_names() -> None:
    assert camera_key("/cam/color/image_raw") == "observation.images.cam_color_image_raw"
    assert urdf_joint_order(URDF) == (("shoulder", "elbow"), "two_joint_arm")
