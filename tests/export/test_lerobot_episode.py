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


def test_a_camera_only_bag_with_raw_and_h264_video_topics(tmp_path: Path) -> None:
    """Issue 38's camera bag (tests/camerabag.py): /camera/image_raw (rgb8) and /front/video (H.264 by PyAV's x264,
    the same scene at half size); no joint states: cameras alone make an episode. Decoded back with PyAV."""
    import av
    from camerabag import Frames, write_camera_video_bag
    from lerobotbags import held
    from rosbags.rosbag2 import Reader

    write_camera_video_bag(tmp_path / "cam", 10, rate=15.0)  # 640x480, the video 320x240
    (tmp_path / "out").mkdir()
    part = export_episode(EpisodeSpec(tmp_path / "cam", tmp_path / "out", fps=15, codec="h264"))
    assert part.state is None and part.cameras == {
        "observation.images.camera_image_raw": (480, 640),
        "observation.images.front_video": (240, 320),
    }
    with Reader(tmp_path / "cam") as reader:
        times = {c.topic: [t for _, t, _ in reader.messages(connections=[c])] for c in reader.connections}
    frames_ns = part.start_ns + np.arange(part.frames) * 1_000_000_000 // 15
    scene = Frames()
    for key, topic, scale in (("camera_image_raw", "/camera/image_raw", 1), ("front_video", "/front/video", 2)):
        with av.open(str(tmp_path / "out" / f"observation.images.{key}.mp4")) as container:
            got = [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]
        shown = held(times[topic], frames_ns)
        assert len(got) == part.frames
        for frame, k in zip(got, shown, strict=True):
            # /front/video's message k carries x264's frame k (zerolatency: no delay); the raw topic's is image k
            want = scene(int(k))[::scale, ::scale]
            w = np.array([0.299, 0.587, 0.114])
            mse = np.mean((frame.astype(float) @ w - want.astype(float) @ w) ** 2)
            assert 10 * np.log10(255**2 / mse) >= 30.0, (key, k)


def test_time_header_takes_the_stamps(tmp_path: Path) -> None:
    """Images stamped 25 ms before they were received: on receive times the episode starts with the first image
    (40 ms), on header stamps with the first command (20 ms; the first image is stamped 15 ms)."""
    from bagmaker import T0

    bag = write_arm_bag(tmp_path / "bag", seconds=0.5, camera_lag_ns=25_000_000)
    receive = export_episode(EpisodeSpec(bag.path, tmp_path, fps=10, action="/arm_controller/joint_trajectory"))
    header = export_episode(
        EpisodeSpec(bag.path, tmp_path, fps=10, action="/arm_controller/joint_trajectory", header_time=True)
    )
    assert receive.start_ns == T0 + 40_000_000 and header.start_ns == T0 + 20_000_000
    assert (receive.frames, header.frames) == (4, 5)  # to the last command, 0.42 s: 0.04 .. 0.34 s; 0.02 .. 0.42 s
