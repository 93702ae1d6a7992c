"""How a run is shown: the tutorial keeps r2d2.rviz's view; other robots get its orbit angles, fitted."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import default_urdf_path, load_urdf
from r2d2_viz.sources.motion import make_motion
from r2d2_viz.sources.plan import RunPlan, plan_motion
from r2d2_viz.viewer.layout.plan import plan_view

ARM = REPO / "examples" / "arm6.urdf"
YAW, PITCH = 4.618575572967529, 0.459797203540802  # r2d2.rviz's Views / Current


def _plan(urdf: Path, motion: str | None = None) -> RunPlan:
    robot = load_urdf(urdf)
    return plan_motion(compile_tree(robot), make_motion(robot, motion, n_samples=10), "odom")


def test_the_tutorial_keeps_its_exact_view() -> None:
    view = plan_view(_plan(default_urdf_path()), rviz=None, fixed_frame=None)
    assert view.layout.camera is None  # r2d2.rviz's own camera
    assert view.axis_length == 0.1 and view.layout.limited == 2 and view.layout.continuous == 1
    assert view.notes == () and view.layout.fixed_frame == "odom"


def test_another_robot_gets_the_same_orbit_angles_fitted_to_it() -> None:
    view = plan_view(_plan(ARM), rviz=None, fixed_frame=None)
    camera = view.layout.camera
    assert camera is not None
    d = np.subtract(camera.eye, camera.target)
    assert math.atan2(d[1], d[0]) % (2 * math.pi) == pytest.approx(YAW, abs=1e-9)
    assert math.asin(d[2] / np.linalg.norm(d)) == pytest.approx(PITCH, abs=1e-9)
    assert 1.0 < np.linalg.norm(d) < 5.0  # a 1 m arm is looked at from metres away, not r2d2.rviz's 10 m
    assert camera.target[2] > 0.2  # the focal point is up the arm, not at odom's origin
    assert 0.05 < view.axis_length < 0.2 and view.layout.show_arrows  # marker scale ~ the arm's ~1.3 m reach
    assert view.layout.limited == 4 and view.layout.continuous == 2  # arm6: 3 revolute + 1 prismatic, 2 continuous


def test_an_rviz_config_wins_and_a_missing_fixed_frame_is_said(tmp_path: Path) -> None:
    config = REPO / "tests" / "data" / "rviz" / "turtlebot3_navigation_ros1.rviz"
    view = plan_view(_plan(ARM), rviz=config, fixed_frame=None)
    assert view.layout.camera is None and view.layout.fixed_frame == "map"
    assert any("Fixed Frame [map] does not exist" in n for n in view.notes)
    override = plan_view(_plan(ARM), rviz=config, fixed_frame="odom")
    assert override.layout.fixed_frame == "odom" and not any("Fixed Frame" in n for n in override.notes)


def test_without_a_config_every_image_topic_gets_a_2d_view() -> None:
    plan = RunPlan(None, "odom", displays={"/cam/image_raw": "sensor_msgs/msg/Image", "/scan": "x"})
    topics = plan_view(plan, rviz=None, fixed_frame=None).spec.topics
    assert [(t.kind, t.topic) for t in topics] == [("Image", "/cam/image_raw")]


def _markers_in(frame: str) -> bytes:
    from msgs_build import T, cdr, header, marker_msg, pose, vec

    marker = marker_msg(1, header=header(frame), ns="person", id=1, pose=pose(1, 0, 0), scale=vec(1, 1, 1))
    return cdr(T("visualization_msgs/msg/MarkerArray")(markers=[marker]))


def _tf_plan(displays: dict[str, tuple[str, bytes]]) -> RunPlan:
    """``odom`` → ``base_link`` (/tf) → ``laser`` (/tf_static), and one message on each display topic."""
    from r2d2_viz.sources.bag_displays import TopicMessage
    from r2d2_viz.sources.base import TfRecords

    def records(parent: str, child: str, *, static: bool) -> TfRecords:
        return TfRecords(
            np.zeros(1, np.int64), (parent,), (child,), np.zeros((1, 3)), np.array([[0, 0, 0, 1.0]]), static
        )

    messages = [TopicMessage(k, topic, msgtype, data) for k, (topic, (msgtype, data)) in enumerate(displays.items())]
    return RunPlan(
        None,
        "odom",
        static_tf=records("base_link", "laser", static=True),
        moving_tf=records("odom", "base_link", static=False),
        displays={topic: msgtype for topic, (msgtype, _) in displays.items()},
        preview_messages=tuple(messages),
    )


def test_a_display_frame_no_transform_reaches_is_said_once_in_rvizs_words() -> None:
    # RViz's Marker display on a frame with no transform to the fixed frame: "No transform from [person] to [odom]"
    array = "visualization_msgs/msg/MarkerArray"
    plan = _tf_plan({"/people": (array, _markers_in("person")), "/near": (array, _markers_in("laser"))})
    view = plan_view(plan, rviz=None, fixed_frame=None)
    lines = [n for n in view.notes if "No transform" in n]
    assert lines == [
        "/people: No transform from [person] to [odom]: nothing joins them in the bag's transforms; not shown "
        "(RViz says the same)"
    ]
    # /near's laser is two transforms from odom: reached, not said
    assert not any("/near" in n for n in view.notes)


def test_image_topics_without_a_camera_info_stay_out_of_the_3d_view() -> None:
    # /cam's CameraInfo gives /cam/image_raw a pinhole (RViz's Camera display pairs them by namespace); /bare has none
    displays = {
        "/cam/image_raw": "sensor_msgs/msg/Image",
        "/cam/camera_info": "sensor_msgs/msg/CameraInfo",
        "/bare/image": "sensor_msgs/msg/CompressedImage",
    }
    plan = RunPlan(None, "odom", displays=displays)
    assert plan_view(plan, rviz=None, fixed_frame=None).layout.flat_images == ("/bare/image",)
