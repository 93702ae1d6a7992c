"""What the tools draw, read back from an .rrd with Rerun's reader: the ground at z = 0 around the fixed frame, an
arrow along the heading, a sphere at the point, the measured line with its length, each in the fixed frame."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import rerun as rr
from rrd import read_recording

from r2d2_viz.viewer.web.draw import GROUND, ToolDrawing


def test_ground_pose_point_and_measure(tmp_path: Path) -> None:
    out = tmp_path / "out.rrd"
    rec = rr.RecordingStream("test_draw")
    rec.save(out)
    draw = ToolDrawing(rec, "map")
    draw.ground((-80.0, -10.0, 5.0, 10.0), background=(48, 48, 48))
    draw.pose("/goal_pose", (1.0, 2.0, 0.0), math.pi / 2)
    draw.point("/clicked_point", (1.5, -2.0, 0.3))
    draw.measure((0.0, 0.0, 0.0), (3.0, 4.0, 0.0), 5.0)
    rec.flush()
    rec.disconnect()
    rows = read_recording(out)
    for entity in (GROUND, "/tools/goal_pose", "/tools/clicked_point", "/tools/measure"):
        frames = [v for k, v in rows[entity].static.items() if "CoordinateFrame" in k]
        assert frames and frames[0][0] == ["map"], entity
    ground = next(v for k, v in rows[GROUND].static.items() if "vertex_positions" in k)[0]
    corners = np.array(ground)
    assert np.array_equal(corners[:, 2], np.zeros(4)) and corners[:, 0].min() == -80 and corners[:, 1].max() == 50
    albedo = next(v for k, v in rows[GROUND].static.items() if "albedo_factor" in k)[0]
    assert albedo[0] >> 8 == 0x303030 and 0 < albedo[0] & 0xFF < 16  # RViz's background, nearly transparent
    vector = next(v for k, v in rows["/tools/goal_pose"].static.items() if "vectors" in k)[0][0]
    assert np.allclose(vector, [0, 1, 0], atol=1e-6)  # heading 90°: along +y
    center = next(v for k, v in rows["/tools/clicked_point"].static.items() if "centers" in k)[0][0]
    assert np.allclose(center, [1.5, -2.0, 0.3])
    labels = next(v for k, v in rows["/tools/measure"].static.items() if "labels" in k)[0]
    assert labels == ["5.000 m"]
