"""The ``--compare`` layout, read back from the blueprint file it saves."""

from __future__ import annotations

from pathlib import Path

from rrd import blueprint_components

from r2d2_viz.viewer.compare.layout import compare_blueprint


def test_one_3d_view_in_the_compare_frame_and_each_plot_overlaid_across_runs(tmp_path: Path) -> None:
    out = tmp_path / "compare.rbl"
    eye = {"position": [1.0, 2.0, 3.0], "look_target": [0.0, 0.0, 0.0], "eye_up": [0.0, 0.0, 1.0]}
    hidden = {"b": ["/robot/collision"]}
    compare_blueprint(["a", "b"], [["/odom.twist.twist.linear.x"]], eye, hidden).save("r2d2_viz", out)
    parts = blueprint_components(out)
    queries = [c["ViewContents:query"] for c in parts.values() if "ViewContents:query" in c]
    assert ["+ /runs/a/plot/0/**", "+ /runs/b/plot/0/**"] in queries
    assert ["+ /runs/a/joints/**", "+ /runs/b/joints/**"] in queries
    scene = next(q for q in queries if "+ /runs/**" in q)
    assert "- /runs/b/plot/**" in scene and "- /runs/a/warnings" in scene
    frames = [c["SpatialInformation:target_frame"] for c in parts.values() if "SpatialInformation:target_frame" in c]
    assert frames == [["compare"]]
    eyes = [c["EyeControls3D:position"] for c in parts.values() if "EyeControls3D:position" in c]
    assert eyes == [[[1.0, 2.0, 3.0]]]
    off = [path for path, c in parts.items() if c.get("EntityBehavior:visible") == [False]]
    assert [path.partition("/ViewContents/overrides")[2] for path in off] == ["/runs/b/robot/collision/visualizers"]
