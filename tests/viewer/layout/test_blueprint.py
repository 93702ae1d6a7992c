"""The RViz-like blueprint: values read off r2d2.rviz, embedded in every recording, saved to blueprints/."""

from __future__ import annotations

import pytest
from conftest import REPO
from rrd import blueprint_components

from r2d2_viz.viewer.layout.blueprint import generate_blueprint, save_blueprint

CHECKED_IN = REPO / "blueprints" / "r2d2.rbl"


@pytest.fixture(scope="module")
def fresh(tmp_path_factory: pytest.TempPathFactory) -> dict:
    return blueprint_components(save_blueprint(tmp_path_factory.mktemp("bp") / "r2d2.rbl"))


def _view(components: dict, class_identifier: str, name: str | None = None) -> str:
    matches = [
        path
        for path, c in components.items()
        if c.get("ViewBlueprint:class_identifier") == [class_identifier]
        and (name is None or c.get("ViewBlueprint:display_name") == [name])
    ]
    assert len(matches) == 1, (class_identifier, name, matches)
    return matches[0]


def test_checked_in_blueprint_is_not_stale(fresh: dict) -> None:
    assert blueprint_components(CHECKED_IN) == fresh, (
        "blueprints/r2d2.rbl differs from generate_blueprint(); regenerate it with: python -m r2d2_viz.blueprint"
    )


def _rgba(packed: int) -> tuple[int, int, int, int]:
    return ((packed >> 24) & 255, (packed >> 16) & 255, (packed >> 8) & 255, packed & 255)


def test_mirrors_r2d2_rviz(fresh: dict) -> None:
    view = _view(fresh, "3D")
    assert fresh[view]["ViewBlueprint:space_origin"] == ["/"]
    # Global Options: Fixed Frame odom, Background Color 48; 48; 48
    assert fresh[f"{view}/SpatialInformation"]["SpatialInformation:target_frame"] == ["odom"]
    assert _rgba(fresh[f"{view}/Background"]["Background:color"][0])[:3] == (48, 48, 48)
    # Grid: Cell Size 1, Plane XY, Color 160; 160; 164, Alpha 0.5
    grid = fresh[f"{view}/LineGrid3D"]
    assert grid["LineGrid3D:visible"] == [True] and grid["LineGrid3D:spacing"] == [1.0]
    assert grid["LineGrid3D:plane"] == [[0.0, 0.0, 1.0, 0.0]]
    assert _rgba(grid["LineGrid3D:color"][0]) == (160, 160, 164, 128)
    # Views: Orbit, distance 10, yaw 4.6186, pitch 0.4598, focal point 0 → eye ≈ (−0.84, −8.92, 4.44) (issue #2)
    eye = fresh[f"{view}/EyeControls3D"]
    assert eye["EyeControls3D:position"][0] == pytest.approx([-0.84, -8.92, 4.44], abs=0.01)
    assert eye["EyeControls3D:look_target"] == [[0.0, 0.0, 0.0]] and eye["EyeControls3D:eye_up"] == [[0.0, 0.0, 1.0]]
    # RobotModel: Collision Enabled false → the collision subtree is hidden; visuals shown
    hidden = fresh[f"{view}/ViewContents/overrides/robot/collision/visualizers"]
    assert hidden["EntityBehavior:visible"] == [False]
    # plus the joint plots
    assert fresh[_view(fresh, "TimeSeries", "Joint states")]["ViewBlueprint:space_origin"] == ["/joints/limited"]


def test_every_recording_embeds_it(lap_recording) -> None:
    assert blueprint_components(lap_recording[0]) == blueprint_components(CHECKED_IN)


def test_generate_blueprint_is_pure() -> None:
    a, b = generate_blueprint(), generate_blueprint()
    assert [p.id for p in a.root_container.contents] == [p.id for p in b.root_container.contents]  # type: ignore[union-attr]


def test_the_layout_follows_the_robot(tmp_path) -> None:
    from r2d2_viz.viewer.layout.blueprint import Layout

    def components(layout: Layout) -> dict:
        path = tmp_path / "b.rbl"
        generate_blueprint(layout=layout).save("r2d2_viz", path)
        return blueprint_components(path)

    names = lambda c: {v.get("ViewBlueprint:display_name", [None])[0] for v in c.values()}  # noqa: E731
    arm = components(Layout(limited=5, continuous=0, fixed_frame="map"))
    assert "Continuous joints" not in names(arm) and "Joint states" in names(arm)  # no empty panels
    assert arm[f"{_view(arm, '3D')}/SpatialInformation"]["SpatialInformation:target_frame"] == ["map"]
    humanoid = components(Layout(limited=30, continuous=0))
    plot = _view(humanoid, "TimeSeries", "Joint states")
    assert humanoid[f"{plot}/PlotLegend"]["PlotLegend:visible"] == [False]  # 30 names would cover the plot
    query = humanoid[f"{plot}/ViewContents"]["ViewContents:query"]
    assert "- /joints/limited/limits" in query  # and the 60 limit lines are left out
    small = components(Layout(limited=5, continuous=0))
    assert f"{_view(small, 'TimeSeries', 'Joint states')}/PlotLegend" not in small


# --------------------------------------------------------------------------------------------------
# RViz's Decay Time → each drawn entity's visible time range

DECAY_CONFIG = """
Visualization Manager:
  Global Options: {Fixed Frame: odom}
  Displays:
    - {Class: rviz_default_plugins/LaserScan, Name: five, Enabled: true, Topic: {Value: /scan}, Decay Time: 5}
    - {Class: rviz_default_plugins/PointCloud2, Name: half, Enabled: true, Topic: {Value: /points}, Decay Time: 2.5}
    - {Class: rviz_default_plugins/LaserScan, Name: latest, Enabled: true, Topic: {Value: /scan0}, Decay Time: 0}
    - {Class: rviz_default_plugins/LaserScan, Name: unset, Enabled: true, Topic: {Value: /scan_unset}}
    - {Class: rviz_default_plugins/LaserScan, Name: off, Enabled: false, Topic: {Value: /scan_off}, Decay Time: 5}
    - {Class: rviz_default_plugins/Odometry, Name: odom, Enabled: true, Topic: {Value: /odom}, Keep: 3,
       Decay Time: 1, Covariance: {Value: false}}
    - {Class: rviz_default_plugins/Odometry, Name: cov, Enabled: true, Topic: {Value: /odom_cov}, Keep: 2,
       Decay Time: 1, Covariance: {Value: true}}
    - {Class: rviz_default_plugins/PoseWithCovariance, Name: amcl, Enabled: true, Topic: {Value: /amcl},
       Decay Time: 3}
    - {Class: rviz_default_plugins/Range, Name: sonar, Enabled: true, Topic: {Value: /sonar}, Decay Time: 4}
    - {Class: rviz_default_plugins/MarkerArray, Name: markers, Enabled: true, Topic: {Value: /markers},
       Decay Time: 5}
"""


def _decay_ranges(components: dict) -> dict[str, object]:
    """Override entity → its VisibleTimeRanges, read back from the saved blueprint."""
    (view,) = [p for p, c in components.items() if c.get("ViewBlueprint:class_identifier") == ["3D"]]
    prefix = f"{view}/ViewContents/overrides"
    return {
        p[len(prefix) : -len("/visualizers")]: c["VisibleTimeRanges:ranges"]
        for p, c in components.items()
        if p.startswith(prefix) and "VisibleTimeRanges:ranges" in c
    }


def test_decay_time_becomes_each_drawn_entitys_visible_time_range(tmp_path) -> None:
    from r2d2_viz.rviz.config import parse_rviz

    path = tmp_path / "decay.rbl"
    generate_blueprint(parse_rviz(DECAY_CONFIG, source="decay.rviz")).save("r2d2_viz", path)
    got = _decay_ranges(blueprint_components(path))

    def last(seconds: float) -> list[dict]:  # the last N seconds up to the cursor, on the bag's timeline
        return [{"timeline": "time", "range": {"start": -round(seconds * 1e9), "end": 0}}]

    # by hand from DECAY_CONFIG: 0, unset and disabled displays keep the latest message (no range); Odometry's
    # Keep 3 slots /odom/0..2, with Covariance each slot's arrow and ellipsoid (/odom_cov/k/0, /1); a
    # PoseWithCovariance draws an arrow and an ellipsoid (/amcl/0, /amcl/1); markers: none (known from the data)
    expected = {
        "/scan": last(5),
        "/points": last(2.5),
        **{f"/odom/{k}": last(1) for k in range(3)},
        **{f"/odom_cov/{k}/{i}": last(1) for k in range(2) for i in range(2)},
        "/amcl/0": last(3),
        "/amcl/1": last(3),
        "/sonar": last(4),
    }
    assert got == expected


def test_decay_reaches_the_entities_a_recording_draws_on(tmp_path) -> None:
    """The overrides name the very entities the app logs the topics' drawings on (an override on a parent does
    not reach its children: checked in the viewer, tests/e2e/test_decay_e2e.py): read from a recording of a
    rosbags-written bag, with the config's decay on its scan and its odometry."""
    from conftest import cli
    from displaybags import write_display_bag
    from rrd import read_recording

    bag = write_display_bag(tmp_path / "bag")
    config = tmp_path / "decay.rviz"
    config.write_text(
        "Visualization Manager:\n  Global Options: {Fixed Frame: odom}\n  Displays:\n"
        "    - {Class: rviz_default_plugins/LaserScan, Enabled: true, Topic: {Value: /scan}, Decay Time: 5}\n"
        "    - {Class: rviz_default_plugins/Odometry, Enabled: true, Topic: {Value: /odom}, Keep: 4,"
        " Decay Time: 2}\n"
    )
    out = tmp_path / "run.rrd"
    run = cli("--bag", str(bag), "--rviz", str(config), "--save", str(out))
    assert run.returncode == 0, run.stderr
    ranges = _decay_ranges(blueprint_components(out))
    drawn = {
        entity
        for entity, rows in read_recording(out).items()
        if entity.split("/")[1] in ("scan", "odom")
        and any(name.startswith(("Points3D:", "Arrows3D:")) for name in rows.temporal)
    }
    # the bag's 3 odometry messages fill slots 0..2 of the 4; the scans are all on /scan
    assert drawn == {"/scan", "/odom/0", "/odom/1", "/odom/2"}
    assert drawn <= set(ranges) and set(ranges) == {"/scan", *(f"/odom/{k}" for k in range(4))}


def test_images_without_a_pinhole_are_left_out_of_the_3d_view(tmp_path) -> None:
    from r2d2_viz.viewer.layout.blueprint import Layout

    path = tmp_path / "flat.rbl"
    generate_blueprint(layout=Layout(flat_images=("/bare/image",))).save("r2d2_viz", path)
    components = blueprint_components(path)
    view = _view(components, "3D")
    # the 3D view cannot place an image without a pinhole ("2D visualizers require a pinhole ancestor"): out
    assert components[f"{view}/ViewContents"]["ViewContents:query"][-1] == "- /bare/image/**"


def test_each_robot_takes_the_robot_model_display_of_its_description_topic() -> None:
    from r2d2_viz.rviz.spec import RobotModel, ViewSpec
    from r2d2_viz.viewer.layout.blueprint import robot_display

    default = RobotModel()
    two = RobotModel(collision=True, description_topic="/robot2/robot_description", tf_prefix="robot2")
    spec = ViewSpec("x.rviz", robot=default, more_robots=(two,))
    assert robot_display(spec, "/robot2") is two
    assert robot_display(spec, "/robot1") is default  # a display for /robot_description draws the others
    assert robot_display(ViewSpec("x.rviz", robot=two), "/robot1") is None  # no display draws robot1: hidden


def test_a_log_diagnostics_a_map_and_plots_each_get_a_view_below_only_when_there_are_some(
    tmp_path, fresh: dict
) -> None:
    from r2d2_viz.viewer.layout.blueprint import Layout

    kinds = {"TextLog", "StateTimeline", "Map", "TimeSeries"}
    plain = {c["ViewBlueprint:class_identifier"][0] for c in fresh.values() if "ViewBlueprint:class_identifier" in c}
    assert plain & kinds == {"TextLog", "TimeSeries"}  # the tutorial's: its warnings and joint plots, nothing new
    path = tmp_path / "telemetry.rbl"
    layout = Layout(
        logs=("/rosout",), states=("/diagnostics", "/diagnostics_agg"), maps=("/fix",), plots=("/imu", "/b")
    )
    generate_blueprint(layout=layout).save("r2d2_viz", path)
    components = blueprint_components(path)
    states = ["+ /diagnostics/**", "+ /diagnostics_agg/**"]
    for kind, name, query in [
        ("TextLog", "Log: /rosout", ["+ /rosout/**"]),
        ("StateTimeline", "Diagnostics: /diagnostics · /diagnostics_agg", states),
        ("Map", "Map: /fix", ["+ /fix/**"]),
        ("TimeSeries", "/imu", ["$origin/**"]),  # a plot per topic (their units differ), as tabs
        ("TimeSeries", "/b", ["$origin/**"]),
    ]:
        view = _view(components, kind, name)
        assert components[f"{view}/ViewContents"]["ViewContents:query"] == query
    # the log's level and text come first (a node's lines are long)
    [tabs] = [c for c in components.values() if c.get("ContainerBlueprint:display_name") == ["Sensors"]]
    assert tabs["ContainerBlueprint:container_kind"] == [1] and len(tabs["ContainerBlueprint:contents"]) == 2  # Tabs
    log = _view(components, "TextLog", "Log: /rosout")
    columns = components[f"{log}/TextLogColumns"]["TextLogColumns:text_log_columns"]
    assert [c["kind"] for c in columns] == [2, 3, 1]  # LogLevel, Body, EntityPath (TextLogColumnKind)


def test_regenerating_leaves_the_committed_file_as_it_is(tmp_path) -> None:
    """``python -m r2d2_viz.blueprint`` wrote new bytes on every run, so ``git status`` always showed the committed
    ``blueprints/r2d2.rbl`` as modified (issue 36; Rerun mints new ids on every save). As the README runs it, from
    a checkout (here a copy of the committed file): twice, and the bytes stay the committed ones; a layout that
    changed (an RViz config converted over it) is still written."""
    import shutil
    import subprocess
    import sys

    (tmp_path / "blueprints").mkdir()
    committed = tmp_path / "blueprints" / "r2d2.rbl"
    shutil.copy(CHECKED_IN, committed)
    for _ in range(2):
        done = subprocess.run(
            [sys.executable, "-m", "r2d2_viz.blueprint"], cwd=tmp_path, capture_output=True, timeout=120
        )
        assert done.returncode == 0, done.stderr
        assert committed.read_bytes() == CHECKED_IN.read_bytes()
    assert sorted(p.name for p in committed.parent.iterdir()) == ["r2d2.rbl"]  # no partial file left
    rviz = REPO / "tests" / "data" / "rviz" / "turtlebot3_model.rviz"
    args = [sys.executable, "-m", "r2d2_viz.blueprint", "--rviz", str(rviz), str(committed)]
    assert subprocess.run(args, cwd=tmp_path, capture_output=True, timeout=120).returncode == 0
    assert blueprint_components(committed) != blueprint_components(CHECKED_IN)
