"""The viewer layout: Rerun's counterpart of the tutorial's ``r2d2.rviz``.

r2d2.rviz shows one 3D view in the fixed frame ``odom`` with three displays — Grid, TF and
RobotModel — and an Orbit camera. :func:`generate_blueprint` builds the same as a Rerun blueprint,
plus a plot of the joint values (what ``ros2 topic echo /joint_states`` would print) and a log of
warnings. It is a pure function of nothing: the same layout serves every URDF.

Save it with ``python -m r2d2_viz.blueprint [PATH]`` (default ``blueprints/r2d2.rbl``).
"""

from __future__ import annotations

import math
import sys
import uuid
from collections.abc import Sequence
from pathlib import Path

import rerun as rr
import rerun.blueprint as rrb

from .entities import APP_ID, TIMELINE, path
from .motion import ODOM

# --- values read off r2d2.rviz --------------------------------------------------------------------
BACKGROUND_RGB = (48, 48, 48)  # Global Options / Background Color
GRID_RGB = (160, 160, 164)  # Grid / Color
GRID_ALPHA = 0.5  # Grid / Alpha
GRID_CELL_SIZE_M = 1.0  # Grid / Cell Size
ORBIT_DISTANCE = 10.0  # Views / Current / Distance
ORBIT_YAW = 4.618575572967529  # Views / Current / Yaw
ORBIT_PITCH = 0.459797203540802  # Views / Current / Pitch
ORBIT_FOCAL_POINT = (0.0, 0.0, 0.0)  # Views / Current / Focal Point

DEFAULT_BLUEPRINT_PATH = Path("blueprints/r2d2.rbl")
_ID_NAMESPACE = uuid.UUID("5f1b7a52-3c1e-4d0e-9a43-6b2f3f2d2d20")


def _stable_id(part: rrb.View | rrb.Container, key: str) -> None:
    """Name-derived ids instead of random ones, so the saved blueprint is the same on every save."""
    part.id = uuid.uuid5(_ID_NAMESPACE, key)


def orbit_eye_position(
    distance: float = ORBIT_DISTANCE,
    yaw: float = ORBIT_YAW,
    pitch: float = ORBIT_PITCH,
    focal_point: tuple[float, float, float] = ORBIT_FOCAL_POINT,
) -> tuple[float, float, float]:
    """Where RViz's Orbit view puts the eye (Z up): on a sphere of radius ``distance`` around the focal point."""
    fx, fy, fz = focal_point
    return (
        fx + distance * math.cos(pitch) * math.cos(yaw),
        fy + distance * math.cos(pitch) * math.sin(yaw),
        fz + distance * math.sin(pitch),
    )


def generate_blueprint(*, hidden_links: Sequence[str] = ()) -> rrb.Blueprint:
    """The RViz-like layout: a 3D view in ``odom`` (Grid, TF, RobotModel), joint plots, warnings.

    ``hidden_links`` hides those links' visuals, like unticking them under RobotModel / Links in RViz.
    """
    overrides: dict[str, rrb.EntityBehavior] = {"/robot/collision": rrb.EntityBehavior(visible=False)}
    overrides.update({path("robot", "visual", link): rrb.EntityBehavior(visible=False) for link in hidden_links})
    scene = rrb.Spatial3DView(
        name="3D: odom (Grid · TF · RobotModel)",
        origin="/",
        contents=["+ /**", "- /joints/**", "- /warnings"],
        background=rrb.Background(color=BACKGROUND_RGB),
        line_grid=rrb.LineGrid3D(
            visible=True,
            spacing=GRID_CELL_SIZE_M,
            plane=rr.components.Plane3D.XY,
            stroke_width=1.0,
            color=(*GRID_RGB, round(255 * GRID_ALPHA)),
        ),
        spatial_information=rrb.SpatialInformation(target_frame=ODOM, show_axes=False, show_bounding_box=False),
        eye_controls=rrb.EyeControls3D(
            kind=rrb.Eye3DKind.Orbital,
            position=orbit_eye_position(),
            look_target=ORBIT_FOCAL_POINT,
            eye_up=(0.0, 0.0, 1.0),
        ),
        # RobotModel: "Collision Enabled: false" — collision shapes are logged but hidden.
        overrides=overrides,  # type: ignore[arg-type]  # EntityBehavior is one of the accepted values
    )
    # /joint_states as plots: joints with limits (and the limits), and continuous joints, which
    # grow without bound (the tutorial's swivel) and would flatten the others on a shared axis.
    limited = rrb.TimeSeriesView(name="Joint states", origin="/joints/limited")
    continuous = rrb.TimeSeriesView(name="Continuous joints", origin="/joints/continuous")
    log = rrb.TextLogView(name="Warnings", origin="/warnings")
    side = rrb.Vertical(limited, continuous, log, row_shares=[3, 2, 1])
    root = rrb.Horizontal(scene, side, column_shares=[2, 1])
    parts: dict[str, rrb.View | rrb.Container] = {
        "scene": scene,
        "limited": limited,
        "continuous": continuous,
        "log": log,
        "side": side,
        "root": root,
    }
    for key, part in parts.items():
        _stable_id(part, key)
    return rrb.Blueprint(
        root,
        rrb.BlueprintPanel(state=rrb.components.PanelState.Expanded),
        rrb.SelectionPanel(state=rrb.components.PanelState.Collapsed),
        # Play state left to the viewer: a recording plays once from the start and stays on its last
        # frame; a live stream is followed as it arrives — RViz always shows the latest state.
        rrb.TimePanel(state=rrb.components.PanelState.Collapsed, timeline=TIMELINE),
        auto_views=False,
    )


def save_blueprint(path: Path = DEFAULT_BLUEPRINT_PATH) -> Path:
    """Write :func:`generate_blueprint` as an ``.rbl`` file for ``rerun FILE.rrd PATH.rbl``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    generate_blueprint().save(APP_ID, path)
    return path


if __name__ == "__main__":  # python -m r2d2_viz.blueprint [PATH]
    print(save_blueprint(Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_BLUEPRINT_PATH))
