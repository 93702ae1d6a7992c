"""The layout of a ``--compare`` recording: one 3D view of every run's robot (in :data:`COMPARE_FRAME`), the joint
states of every run in one plot, each ``--plot`` flag's series of every run in one plot, the differences as text
and every run's warnings."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import rerun.blueprint as rrb

from r2d2_viz.viewer.compare.merge import RUNS
from r2d2_viz.viewer.compare.scene import COMPARE_FRAME, SUMMARY
from r2d2_viz.viewer.entities import TIMELINE, WARNINGS


def compare_blueprint(
    names: Sequence[str],
    plots: Sequence[Sequence[str]],
    eye: Mapping[str, Sequence[float]] | None = None,
    hidden: Mapping[str, Sequence[str]] | None = None,
) -> rrb.Blueprint:
    """The layout for runs ``names`` (the first the reference), ``plots`` the ``--plot`` flags' paths; ``eye``: the
    first run's 3D camera (``position``, ``look_target``, ``eye_up``), else Rerun's own; ``hidden``: run → the
    entities its own layout hides (collision shapes, what its RViz config unticks), hidden in the 3D view too."""
    runs = [f"{RUNS}/{name}" for name in names]
    left_out = [f"- {run}/{part}" for run in runs for part in ("joints/**", "plot/**", WARNINGS.strip("/"))]
    eye_controls = None
    if eye and all(k in eye and len(eye[k]) == 3 for k in ("position", "look_target", "eye_up")):
        eye_controls = rrb.EyeControls3D(
            kind=rrb.Eye3DKind.Orbital,
            position=list(eye["position"]),
            look_target=list(eye["look_target"]),
            eye_up=list(eye["eye_up"]),
        )
    scene = rrb.Spatial3DView(
        name=f"3D: {', '.join(names)} (the first as is, the others as ghosts)"[:120],
        origin="/",
        contents=[f"+ {RUNS}/**", *left_out],
        spatial_information=rrb.SpatialInformation(target_frame=COMPARE_FRAME, show_axes=False),
        eye_controls=eye_controls,
        overrides={  # entity path → hidden
            f"{RUNS}/{name}{entity}": rrb.EntityBehavior(visible=False)
            for name, entities in (hidden or {}).items()
            for entity in entities
        },
    )
    side: list[rrb.View] = [
        rrb.TimeSeriesView(name="Joint states (all runs)", origin="/", contents=[f"+ {run}/joints/**" for run in runs])
    ]
    for n, texts in enumerate(plots):
        side.append(
            rrb.TimeSeriesView(
                name=f"Plot: {', '.join(texts)} (all runs)"[:120],
                origin="/",
                contents=[f"+ {run}/plot/{n}/**" for run in runs],
            )
        )
    text = rrb.TextDocumentView(name="Differences", origin=SUMMARY)
    log = rrb.TextLogView(name="Warnings", origin="/", contents=[f"+ {run}{WARNINGS}" for run in runs])
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(scene, text, row_shares=[3, 1]),
            rrb.Vertical(*side, log, row_shares=[2] * len(side) + [1]),
            column_shares=[2, 1],
        ),
        rrb.BlueprintPanel(state=rrb.components.PanelState.Collapsed),
        rrb.SelectionPanel(state=rrb.components.PanelState.Collapsed),
        rrb.TimePanel(state=rrb.components.PanelState.Collapsed, timeline=TIMELINE),
        auto_views=False,
    )
