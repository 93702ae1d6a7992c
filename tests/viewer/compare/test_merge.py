"""One chunk of a run rewritten for ``--compare``: moved under ``/runs/<name>``, its times shifted onto the
shared timeline (a duration), its frames renamed, a ghost's colours tinted (worked by hand), its series renamed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
from rerun.chunk import Chunk
from rrd import read_recording

from r2d2_viz.viewer.compare.merge import RunFacts, RunStyle, rewrite

T0 = 1_700_000_000_000_000_000


def _sent(tmp_path: Path, chunks: list[Chunk | None]) -> dict:
    out = tmp_path / "out.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    rr.send_chunks([c for c in chunks if c is not None], recording=rec)
    rec.flush()
    rec.disconnect()
    return read_recording(out)


def test_a_chunk_moves_under_its_run_on_the_shared_timeline_with_its_frames_renamed(tmp_path: Path) -> None:
    tf = Chunk.from_columns(
        "/tf",
        [rr.TimeColumn("time", timestamp=np.array([T0 + 5, T0 + 9], "datetime64[ns]"))],
        rr.Transform3D.columns(
            parent_frame=["odom", "odom"], child_frame=["base", "tf#/x"], translation=[[1, 2, 3]] * 2
        ),
    )
    facts = RunFacts()
    recording = _sent(tmp_path, [rewrite(tf, RunStyle("b", -T0 - 5), facts)])
    rows = recording["/runs/b/tf"]
    assert rows.times == [0, 4]
    assert rows.temporal["Transform3D:child_frame"] == [["b/base"], ["tf#/x"]]  # an entity's frame stays its own
    assert rows.temporal["Transform3D:parent_frame"] == [["b/odom"], ["b/odom"]]
    assert facts.frames == {"odom", "base", "tf#/x"} and (facts.first_ns, facts.last_ns) == (T0 + 5, T0 + 9)


def test_a_ghosts_colours_are_tinted_and_its_series_named_after_the_run(tmp_path: Path) -> None:
    mesh = Chunk.from_columns(
        "/robot/visual/body/0",
        [],
        rr.Mesh3D.columns(vertex_positions=[[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], albedo_factor=[0xFFFFFFFF]),
    )
    series = Chunk.from_columns(
        "/joints/limited", [], rr.SeriesLines.columns(names=["tilt", "periscope"]).partition([2])
    )
    recording = _sent(tmp_path, [rewrite(c, RunStyle("b", 0, (255, 140, 0, 100))) for c in (mesh, series)])
    # white blended 15 % white + 85 % tint: (255, 0.15·255 + 0.85·140 = 157.25, 0.15·255 = 38.25); alpha 255·100/255
    assert recording["/runs/b/robot/visual/body/0"].static["Mesh3D:albedo_factor"][-1] == [0xFF9D2664]
    assert recording["/runs/b/joints/limited"].static["SeriesLines:names"][-1] == ["tilt (b)", "periscope (b)"]


def test_the_recordings_properties_stay_out() -> None:
    properties = Chunk.from_columns("/__properties", [], rr.AnyValues.columns(value=["x"]))
    assert rewrite(properties, RunStyle("b", 0)) is None


def test_a_runs_own_layout_says_its_fixed_frame_eye_and_hidden_entities(tmp_path: Path) -> None:
    import rerun.blueprint as rrb

    from r2d2_viz.viewer.compare.merge import blueprint_view

    out = tmp_path / "run.rrd"
    view = rrb.Spatial3DView(
        origin="/",
        spatial_information=rrb.SpatialInformation(target_frame="odom"),
        eye_controls=rrb.EyeControls3D(position=[1, 2, 3], look_target=[0, 0, 0], eye_up=[0, 0, 1]),
        overrides={"/robot/collision": rrb.EntityBehavior(visible=False)},  # type: ignore[dict-item]
    )
    rec = rr.RecordingStream("test")
    rec.save(out, default_blueprint=rrb.Blueprint(view))
    rec.log("/x", rr.Points3D([[0, 0, 0]]))
    rec.flush()
    rec.disconnect()
    run = blueprint_view(out)
    assert (run.frame, run.eye["position"], run.hidden) == ("odom", [1.0, 2.0, 3.0], ["/robot/collision"])
