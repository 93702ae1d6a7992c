"""What the tools draw, read back from an .rrd with Rerun's reader: the ground at z = 0 around the fixed frame (over
the maps' extent when there are maps), an arrow along the heading, a sphere at the point, the measured line with its
length, each in the fixed frame. Extents are computed by hand in the comments."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import rerun as rr
from rrd import read_recording

from r2d2_viz.msgs.shapes import GridMap, Pose
from r2d2_viz.viewer.web.draw import GROUND, ToolDrawing, map_extent

YAW_90 = (0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5))  # xyzw


def _ground(path: Path) -> np.ndarray:
    """The ground's corners the viewer shows: the last static ones logged."""
    rows = read_recording(path)
    return np.array(next(v for k, v in rows[GROUND].static.items() if "vertex_positions" in k)[-1])


def test_map_extent_by_hand() -> None:
    # 400 x 200 cells of 5 cm from (-10, -5): 20 m x 10 m
    assert map_extent(Pose((-10.0, -5.0, 0.0)), 0.05, 400, 200) == (-10.0, -5.0, 10.0, 5.0)
    # turned 90° about its corner (1, 2): 4 x 2 cells of 0.5 m; corner (2, 0) → (1, 4), (2, 1) → (0, 4)
    assert np.allclose(map_extent(Pose((1.0, 2.0, 0.0), YAW_90), 0.5, 4, 2), (0.0, 2.0, 1.0, 4.0))


def test_hostile_maps_are_clamped_or_refused() -> None:
    top = float(np.finfo(np.float32).max)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning either
        # 1e6 x 1e6 cells of 1e38 m: 1e44 m, past float32's 3.4e38
        assert map_extent(Pose(), 1e38, 1_000_000, 1_000_000) == (0.0, 0.0, top, top)
        assert map_extent(Pose((-1e308, 0.0, 0.0)), 1e38, 1_000_000, 1) == (-top, 0.0, -top, 1e38)
        assert map_extent(Pose((math.nan, 0.0, 0.0)), 0.05, 10, 10) is None
        assert map_extent(Pose((math.inf, 0.0, 0.0)), 0.05, 10, 10) is None


def test_ground_covers_the_maps_in_the_fixed_frame(tmp_path: Path) -> None:
    out = tmp_path / "out.rrd"
    rec = rr.RecordingStream("test_draw")
    rec.save(out)
    draw = ToolDrawing(rec, "map")
    draw.ground()
    cells = np.zeros((200, 400, 4), dtype=np.uint8)
    assert draw.cover("map", GridMap(cells, 0.05, Pose((-10.0, -5.0, 0.0))))  # (-10, -5) to (10, 5)
    assert not draw.cover("odom", GridMap(cells, 1.0, Pose()))  # another frame: not transformed, left out
    assert not draw.cover("map", GridMap(cells[:10, :10], 0.05, Pose((0.0, 0.0, 0.0))))  # inside: no redraw
    assert draw.cover("map", GridMap(cells[:10, :10], 1.0, Pose((5.0, 0.0, 0.0))))  # grows x to 15 (y to 10)
    assert draw.extent == (-10.0, -5.0, 15.0, 10.0)
    rec.flush()
    rec.disconnect()
    corners = _ground(out)
    assert np.array_equal(corners, [[-10, -5, 0], [15, -5, 0], [15, 10, 0], [-10, 10, 0]])


def test_ground_pose_point_and_measure(tmp_path: Path) -> None:
    out = tmp_path / "out.rrd"
    rec = rr.RecordingStream("test_draw")
    rec.save(out)
    draw = ToolDrawing(rec, "map", background=(48, 48, 48))
    draw.ground()
    draw.pose("/goal_pose", (1.0, 2.0, 0.0), math.pi / 2)
    draw.point("/clicked_point", (1.5, -2.0, 0.3))
    draw.measure((0.0, 0.0, 0.0), (3.0, 4.0, 0.0), 5.0)
    rec.flush()
    rec.disconnect()
    rows = read_recording(out)
    for entity in (GROUND, "/tools/goal_pose", "/tools/clicked_point", "/tools/measure"):
        frames = [v for k, v in rows[entity].static.items() if "CoordinateFrame" in k]
        assert frames and frames[0][0] == ["map"], entity
    corners = _ground(out)  # no map: 50 m around the origin
    assert np.array_equal(corners, [[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]])
    albedo = next(v for k, v in rows[GROUND].static.items() if "albedo_factor" in k)[0]
    assert albedo[0] >> 8 == 0x303030 and 0 < albedo[0] & 0xFF < 16  # RViz's background, nearly transparent
    vector = next(v for k, v in rows["/tools/goal_pose"].static.items() if "vectors" in k)[0][0]
    assert np.allclose(vector, [0, 1, 0], atol=1e-6)  # heading 90°: along +y
    center = next(v for k, v in rows["/tools/clicked_point"].static.items() if "centers" in k)[0][0]
    assert np.allclose(center, [1.5, -2.0, 0.3])
    labels = next(v for k, v in rows["/tools/measure"].static.items() if "labels" in k)[0]
    assert labels == ["5.000 m"]
