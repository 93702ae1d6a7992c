"""RViz configs from public robot repositories (tests/data/rviz, with their licences) converted to layouts.

Expected values are read off each file by hand; camera positions use RViz's own formulas (rviz_default_plugins:
OrbitViewController::calculatePositionFromYawAndPitch; FixedOrientationOrthoViewController), written out here."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from conftest import REPO, SHARED_REFERENCE, cli
from rrd import blueprint_components

from r2d2_viz.rviz.config import load_rviz, parse_rviz, tutorial_spec
from r2d2_viz.viewer.layout.blueprint import generate_blueprint

DATA = REPO / "tests" / "data" / "rviz"


def _orbit(focal, d, yaw, pitch):
    return (
        focal[0] + d * math.cos(yaw) * math.cos(pitch),
        focal[1] + d * math.sin(yaw) * math.cos(pitch),
        focal[2] + d * math.sin(pitch),
    )


def _blueprint(spec, tmp_path: Path, **kwargs) -> dict:
    path = tmp_path / "converted.rbl"
    generate_blueprint(spec, **kwargs).save("r2d2_viz", path)
    return blueprint_components(path)


def _scene(components: dict) -> str:
    (view,) = [p for p, c in components.items() if c.get("ViewBlueprint:class_identifier") == ["3D"]]
    return view


def _hidden(components: dict, view: str) -> set[str]:
    prefix = f"{view}/ViewContents/overrides"
    return {
        p[len(prefix) : -len("/visualizers")]
        for p, c in components.items()
        if p.startswith(prefix) and c.get("EntityBehavior:visible") == [False]
    }


def _tools_and_panels(spec) -> str:
    """The one note naming the config's tools and panels (none has a counterpart)."""
    lines = [n for n in spec.notes if "no counterpart (Rerun's viewer has its own camera" in n]
    assert len(lines) == 1, spec.notes
    return lines[0]


def test_the_built_in_layout_is_the_tutorials_config(tmp_path: Path) -> None:
    # the repository's own copy of the tutorial's r2d2.rviz (assets/, what the app ships)
    reference = load_rviz(REPO / "assets" / "r2d2.rviz")
    assert tutorial_spec() == reference
    assert _blueprint(reference, tmp_path) == blueprint_components(REPO / "blueprints" / "r2d2.rbl")
    # what it has no counterpart for: four of its eight tools and its four panels (listed by hand from
    # assets/r2d2.rviz), in one line, and the grid's cell count; Measure, SetInitialPose, SetGoal and PublishPoint
    # are on --serve's page (issue 31)
    line = _tools_and_panels(reference)
    tools = ["Interact", "MoveCamera", "Select", "FocusCamera"]
    panels = ["Displays", "Selection", "Tool Properties", "Views"]
    assert line.startswith("r2d2.rviz: 4 tools (") and " and 4 panels (" in line
    assert all(f"rviz_default_plugins/{t}" in line for t in tools) and all(f"rviz_common/{p}" in line for p in panels)
    assert not any(t in line for t in ("Measure", "SetInitialPose", "SetGoal", "PublishPoint"))
    assert len(reference.notes) == 2
    assert any("Plane Cell Count 10" in n for n in reference.notes)


def test_the_json_copy_the_app_reads_is_the_configs_yaml() -> None:
    # assets/r2d2.rviz.json spares a plain run PyYAML's import: it must hold what PyYAML reads from r2d2.rviz
    assert json.loads((REPO / "assets" / "r2d2.rviz.json").read_text()) == yaml.safe_load(
        (REPO / "assets" / "r2d2.rviz").read_text()
    )


def test_the_shipped_config_is_the_tutorials_byte_for_byte() -> None:
    if not (SHARED_REFERENCE / "r2d2.rviz").exists():
        pytest.skip(
            "the ROS 2 tutorial's original r2d2.rviz is not on this machine (it is kept outside the repository); "
            "assets/r2d2.rviz is the repository's copy of it"
        )
    assert (REPO / "assets" / "r2d2.rviz").read_bytes() == (SHARED_REFERENCE / "r2d2.rviz").read_bytes()


def test_turtlebot3_model_ros2_orbit(tmp_path: Path) -> None:
    spec = load_rviz(DATA / "turtlebot3_model.rviz")
    assert spec.fixed_frame == "odom" and spec.background == (48, 48, 48)
    focal = (-0.09679540991783142, -0.015412976033985615, -0.08031613379716873)
    assert spec.camera is not None and spec.camera.kind == "Orbit" and spec.camera.target == pytest.approx(focal)
    assert spec.camera.eye == pytest.approx(_orbit(focal, 7.944110870361328, 3.1454057693481445, 1.5697963237762451))
    assert [(t.kind, t.topic, t.enabled) for t in spec.topics] == [
        ("LaserScan", "/scan", True),
        ("Odometry", "/odom", True),
    ]
    # the displays' style, as the file says (read by hand from tests/data/rviz/turtlebot3_model.rviz)
    scan, odom = (t.style for t in spec.topics)
    assert (scan.color, scan.color_transformer, scan.decay_time) == ((255, 255, 255), "Intensity", 0)
    assert scan.size == pytest.approx(0.01)
    assert (odom.keep, odom.covariance) == (100, False)
    assert not any("cannot draw" in n for n in spec.notes)  # every topic display is drawn now
    components = _blueprint(spec, tmp_path)
    view = _scene(components)
    assert components[f"{view}/SpatialInformation"]["SpatialInformation:target_frame"] == ["odom"]
    eye = components[f"{view}/EyeControls3D"]
    assert eye["EyeControls3D:position"][0] == pytest.approx(spec.camera.eye, abs=1e-5)


def test_turtlebot3_navigation_ros1_top_down(tmp_path: Path) -> None:
    spec = load_rviz(DATA / "turtlebot3_navigation_ros1.rviz")
    assert spec.fixed_frame == "map"
    # TopDownOrtho at X 0, Y 0, Scale 100 px/m, Angle −π/2: straight down from the height that shows 800 px of
    # it (8 m) in a 45° view, the image's up turned by the angle: (−sin a, cos a, 0) = (1, 0, 0)
    height = (800 / 100 / 2) / math.tan(math.radians(22.5))
    assert spec.camera is not None and spec.camera.eye == pytest.approx((0, 0, height))
    assert spec.camera.target == pytest.approx((0, 0, 0)) and spec.camera.up == pytest.approx((1, 0, 0), abs=1e-7)
    assert spec.tf is not None and not spec.tf.enabled  # TF "Enabled: false"
    topics = {t.topic: t for t in spec.topics}
    assert not topics["/raspicam_node/image"].enabled and topics["/scan"].enabled
    assert {"/move_base/DWAPlannerROS/global_plan", "/move_base/local_costmap/footprint"} <= set(topics)  # in groups
    assert "rviz/Time" in _tools_and_panels(spec) and "rviz/SetGoal" not in _tools_and_panels(spec)  # on the page
    components = _blueprint(spec, tmp_path)
    hidden = _hidden(components, _scene(components))
    assert {"/tf_axes", "/tf_arrows", "/tf", "/raspicam_node/image", "/robot/collision"} <= hidden


def test_nav2_default_view_maps_its_particles_and_names_plugins_it_cannot_show() -> None:
    spec = load_rviz(DATA / "nav2_default_view.rviz")
    assert spec.fixed_frame == "map"
    height = (800 / 54 / 2) / math.tan(math.radians(22.5))
    assert spec.camera is not None and spec.camera.eye == pytest.approx((-5.409999847412109, 0, height))
    assert not any("ParticleCloud" in n for n in spec.notes)  # issue 46: AMCL's particles are drawn
    (particles,) = [t for t in spec.topics if t.kind == "ParticleCloud"]
    assert particles.topic == "particle_cloud" and particles.style.color == (0, 180, 0)  # the file's Color
    assert particles.style.shape == "Arrow (Flat)" and particles.style.arrow_lengths == pytest.approx((0.02, 0.3))
    line = _tools_and_panels(spec)  # 7 tools and 7 panels: the lengths of the lists PyYAML reads from the file,
    # less Measure, SetInitialPose and PublishPoint (on --serve's page); Nav2's own GoalTool stays named
    assert "4 tools (" in line and "nav2_rviz_plugins/GoalTool" in line
    assert "7 panels (" in line and "nav2_rviz_plugins/Navigation 2" in line
    assert len(spec.notes) == len(set(spec.notes))  # one line each


def test_turtlebot3_navigation2_and_urdf_tutorial_ros1() -> None:
    nav = load_rviz(DATA / "turtlebot3_navigation2.rviz")
    assert nav.fixed_frame == "map" and nav.camera is not None
    tutorial = load_rviz(DATA / "urdf_tutorial_ros1_urdf.rviz")
    assert tutorial.fixed_frame == "base_link"
    assert tutorial.tf is not None and not tutorial.tf.enabled  # ROS 1's "Value: false" is the checkbox
    assert tutorial.camera is not None and tutorial.camera.eye == pytest.approx(_orbit((0, 0, 0), 1.7, 5.5, 0.33))
    assert any("Alpha 0.8" in n for n in tutorial.notes)


def test_the_cli_lays_out_a_run_as_the_config_says(tmp_path: Path) -> None:
    out = tmp_path / "nav.rrd"
    result = cli("--rviz", str(DATA / "turtlebot3_navigation_ros1.rviz"), "--save", str(out), "--duration", "0.5")
    assert result.returncode == 0, result.stderr
    assert "Fixed Frame [map] does not exist" in result.stderr  # the R2D2 has odom and its links, no map
    # RViz's SetGoal, SetInitialPose and Measure are on --serve's page (issue 31): not named as missing; the
    # camera and selection tools are, once
    assert "rviz/SetGoal" not in result.stderr and "rviz/Measure" not in result.stderr
    assert result.stderr.count("rviz/MoveCamera") == 1
    assert sum("no counterpart (Rerun's viewer has its own camera" in line for line in result.stderr.splitlines()) == 1
    components = blueprint_components(out)
    view = _scene(components)
    assert components[f"{view}/SpatialInformation"]["SpatialInformation:target_frame"] == ["map"]
    bad = cli("--rviz", str(tmp_path / "missing.rviz"), "--save", str(tmp_path / "x.rrd"))
    assert bad.returncode == 2 and "missing.rviz: file not found" in bad.stderr and not (tmp_path / "x.rrd").exists()


def test_python_m_blueprint_converts_a_config(tmp_path: Path) -> None:
    out = tmp_path / "model.rbl"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "r2d2_viz.blueprint",
            "--rviz",
            str(DATA / "turtlebot3_model.rviz"),
            str(out),
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    components = blueprint_components(out)
    assert components[f"{_scene(components)}/SpatialInformation"]["SpatialInformation:target_frame"] == ["odom"]


# RViz's camera maths, written out from the view controllers' sources (independently of r2d2_viz.rviz.config):
# OrbitViewController::updateCamera (eye on the sphere; Invert Z Axis negates yaw and pitch, up is −Z) and
# XYOrbitViewController::updateCamera / ROS 1 ThirdPersonFollowerViewController::updateCamera (the eye moved by
# CAMERA_OFFSET = 0.2 × distance along the camera's up, which Ogre derives from the fixed yaw axis +Z).


def _camera_up(yaw, pitch):
    """Ogre's camera up for a camera at yaw/pitch on the orbit sphere looking at its centre, yaw axis +Z:
    +Z minus its component along the view direction, normalised."""
    d = (math.cos(yaw) * math.cos(pitch), math.sin(yaw) * math.cos(pitch), math.sin(pitch))
    up = [z - d[2] * di for z, di in zip((0, 0, 1), d, strict=True)]
    norm = math.sqrt(sum(u * u for u in up))
    return tuple(u / norm for u in up)


def _xy_orbit(focal, d, yaw, pitch):
    eye = _orbit(focal, d, yaw, pitch)
    up = _camera_up(yaw, pitch)
    lift = tuple(0.2 * d * u for u in up)
    return tuple(e + s for e, s in zip(eye, lift, strict=True)), tuple(f + s for f, s in zip(focal, lift, strict=True))


def test_turtlebot3_burger_ros1_xy_orbit(tmp_path: Path) -> None:
    spec = load_rviz(DATA / "turtlebot3_burger_ros1.rviz")
    # Global Options: Background Color 108; 108; 108, Fixed Frame base_footprint
    assert spec.fixed_frame == "base_footprint" and spec.background == (108, 108, 108)
    # Views / Current: rviz/XYOrbit, Distance 1.910049319267273, Yaw 4.793606281280518, Pitch 0.7953976392745972,
    # Focal Point (-0.02010004222393036, -0.467065691947937, -4.76837158203125e-7)
    focal = (-0.02010004222393036, -0.467065691947937, -4.76837158203125e-7)
    eye, target = _xy_orbit(focal, 1.910049319267273, 4.793606281280518, 0.7953976392745972)
    assert spec.camera is not None and spec.camera.kind == "XYOrbit"
    assert spec.camera.eye == pytest.approx(eye) and spec.camera.target == pytest.approx(target)
    # by hand: yaw ≈ 274.7°, pitch ≈ 45.6°: the eye is south of the focal point (−y) and above it; the lift
    # (0.38 m along the camera's up, which leans north) moves it north and up
    assert spec.camera.eye[1] < focal[1] and spec.camera.eye[2] > 1.3
    assert spec.camera.target[2] == pytest.approx(0.2 * 1.910049319267273 * math.cos(0.7953976392745972), abs=1e-6)
    # TF: Marker Scale 0.4, Show Names true; the rviz/Time panel has no counterpart; the rviz/Axes display is
    # RViz's axes in its Reference Frame (<Fixed Frame> there: the fixed frame)
    assert spec.tf is not None and spec.tf.marker_scale == pytest.approx(0.4) and spec.tf.show_names
    assert not any("rviz/Axes" in n for n in spec.notes)
    assert "rviz/Time" in _tools_and_panels(spec)
    assert [(t.kind, t.topic) for t in spec.topics] == [("Axes", ""), ("LaserScan", "/scan")]
    assert spec.topics[0].style.frame is None
    components = _blueprint(spec, tmp_path)
    view = _scene(components)
    assert components[f"{view}/SpatialInformation"]["SpatialInformation:target_frame"] == ["base_footprint"]
    eye_bp = components[f"{view}/EyeControls3D"]
    assert eye_bp["EyeControls3D:position"][0] == pytest.approx(eye, abs=1e-5)
    assert eye_bp["EyeControls3D:look_target"][0] == pytest.approx(target, abs=1e-5)


def test_universal_robots_ros2_view_robot(tmp_path: Path) -> None:
    spec = load_rviz(DATA / "ur_view_robot.rviz")
    assert spec.fixed_frame == "base_link" and spec.background == (48, 48, 48)
    focal = (-0.0457618348300457, -0.07058511674404144, 0.49734944105148315)
    assert spec.camera is not None and spec.camera.kind == "Orbit"
    assert spec.camera.eye == pytest.approx(_orbit(focal, 3.493516445159912, 0.5353983640670776, 0.15039828419685364))
    assert spec.camera.target == pytest.approx(focal)
    # no TF display in the file: no TF axes or arrows, as in RViz; the RobotModel from a topic is ours
    assert spec.tf is None and spec.robot is not None and spec.robot.visual
    assert _tools_and_panels(spec).count("rviz_default_plugins/") == 4  # 8 tools less the 4 on --serve's page
    components = _blueprint(spec, tmp_path)
    hidden = _hidden(components, _scene(components))
    assert {"/tf_axes", "/tf_arrows", "/tf", "/robot/collision"} <= hidden and "/robot/visual" not in hidden


def test_moveit_panda_shows_the_scene_robot_and_names_the_planning_plugins(tmp_path: Path) -> None:
    spec = load_rviz(DATA / "panda_moveit.rviz")
    assert spec.fixed_frame == "panda_link0"
    focal = (-0.03982115536928177, 0.10271645337343216, 0.17354051768779755)
    assert spec.camera is not None
    assert spec.camera.eye == pytest.approx(_orbit(focal, 2.718453884124756, 0.6603923439979553, 0.5503982305526733))
    # no RobotModel display: MoveIt's PlanningScene draws the robot (Scene Robot: Show Robot Visual true)
    assert spec.robot is not None and spec.robot.visual and not spec.robot.collision
    assert any("moveit_rviz_plugin/PlanningScene: its Scene Robot" in n for n in spec.notes)
    for cls in ("moveit_rviz_plugin/Trajectory", "moveit_rviz_plugin/MotionPlanning"):
        assert sum(f"display {cls}: no counterpart" in n for n in spec.notes) == 1, cls
    assert "rviz_visual_tools/RvizVisualToolsGui" in _tools_and_panels(spec)
    assert [(t.kind, t.topic, t.enabled) for t in spec.topics] == [("MarkerArray", "/rviz_visual_tools", True)]
    components = _blueprint(spec, tmp_path)
    assert "/robot/visual" not in _hidden(components, _scene(components))


def test_unticked_frames_links_and_tf_parts_are_hidden(tmp_path: Path) -> None:
    """turtlebot3's ROS 1 config as RViz saves it after unticking base_scan under TF / Frames,
    wheel_left_link under RobotModel / Links, then Show Arrows (and, second, Show Axes)."""
    text = (DATA / "turtlebot3_burger_ros1.rviz").read_text()
    frames_base_scan = "        base_scan:\n          Value: true\n        caster_back_link:\n          Value: true\n"
    link_wheel_left = (
        "        wheel_left_link:\n          Alpha: 1\n          Show Axes: false\n          Show Trail: false\n"
    )
    assert text.count(frames_base_scan) == 1 and text.count(link_wheel_left) == 1
    text = text.replace(frames_base_scan, frames_base_scan.replace("true\n", "false\n", 1))
    text = text.replace(link_wheel_left + "          Value: true", link_wheel_left + "          Value: false")
    text = text.replace("      Show Arrows: true\n", "      Show Arrows: false\n")
    spec = parse_rviz(text, source="edited.rviz")
    assert spec.tf is not None and spec.tf.hidden_frames == ("base_scan",)
    assert spec.robot is not None and spec.robot.hidden_links == ("wheel_left_link",)
    components = _blueprint(spec, tmp_path)
    hidden = _hidden(components, _scene(components))
    assert {"/tf_axes/base_scan", "/robot/visual/wheel_left_link", "/tf_arrows", "/tf"} <= hidden
    assert "/tf_axes" not in hidden and "/robot/visual" not in hidden
    no_axes = parse_rviz(text.replace("      Show Axes: true\n", "      Show Axes: false\n"), source="edited.rviz")
    components = _blueprint(no_axes, tmp_path)
    assert "/tf_axes" in _hidden(components, _scene(components))


RVIZ2_DISPLAYS = """AccelStamped Axes Camera DepthCloud CameraInfo Effort Grid GridCells FluidPressure Illuminance Image
InteractiveMarkers LaserScan Map PointCloud PointCloud2 Polygon Pose PoseWithCovariance Range RelativeHumidity
RobotModel Temperature TF TwistStamped Marker MarkerArray Odometry PoseArray Path PointStamped Wrench""".split()
"""RViz 2's display classes: ros2/rviz ``rviz_default_plugins/plugins_description.xml`` (rolling, commit f7112b1a),
its entries whose base class is ``rviz_common::Display`` (the tools, view controllers and TF transformer left out)."""


def test_a_config_with_every_rviz2_display_class_converts_without_a_missing_one() -> None:
    path = REPO / "tests" / "data" / "rviz" / "all_displays.rviz"
    classes = [
        line.split("rviz_default_plugins/")[1] for line in path.read_text().splitlines() if "Class: rviz_def" in line
    ]
    assert sorted(classes[:-1]) == sorted(RVIZ2_DISPLAYS) and len(set(RVIZ2_DISPLAYS)) == 32  # (last: the view)
    spec = load_rviz(path)
    assert not [n for n in spec.notes if "no counterpart" in n or "not supported" in n], spec.notes
    drawn = {t.kind for t in spec.topics} | {"Grid", "TF", "RobotModel"}
    assert drawn == set(RVIZ2_DISPLAYS)
