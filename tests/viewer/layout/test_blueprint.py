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


def test_each_robot_takes_the_robot_model_display_of_its_description_topic() -> None:
    from r2d2_viz.rviz.spec import RobotModel, ViewSpec
    from r2d2_viz.viewer.layout.blueprint import robot_display

    default = RobotModel()
    two = RobotModel(collision=True, description_topic="/robot2/robot_description", tf_prefix="robot2")
    spec = ViewSpec("x.rviz", robot=default, more_robots=(two,))
    assert robot_display(spec, "/robot2") is two
    assert robot_display(spec, "/robot1") is default  # a display for /robot_description draws the others
    assert robot_display(ViewSpec("x.rviz", robot=two), "/robot1") is None  # no display draws robot1: hidden
