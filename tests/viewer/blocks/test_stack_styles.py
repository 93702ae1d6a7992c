"""The properties of nav2's ParticleCloud and vision_msgs' Detection3DArray displays, from an .rviz file through
the real CLI: Shape "Arrow (3D)", Color, Min / Max Arrow Length; Only Edge, Line Width, Alpha."""

from __future__ import annotations

import numpy as np
import pytest
from rrd import read_recording
from stackbags import RVIZ, stack_recordings

from r2d2_viz.msgs.shapes import DecodeOptions
from r2d2_viz.rviz.config import load_rviz
from r2d2_viz.rviz.spec import DisplayStyleSpec
from r2d2_viz.viewer.blocks.stack_styles import stack_options


def test_the_config_is_read_without_a_note(tmp_path) -> None:
    path = tmp_path / "stack.rviz"
    path.write_text(RVIZ)
    spec = load_rviz(path)
    assert spec.notes == ()  # both classes have a counterpart now
    kinds = {t.topic: t.kind for t in spec.topics}
    assert kinds == {"/particlecloud": "ParticleCloud", "/detections_3d": "Detection3DArray", "/cam/image_raw": "Image"}


def test_options() -> None:
    assert stack_options(DisplayStyleSpec()) == {}  # nothing set: the displays' defaults
    out = stack_options(DisplayStyleSpec(alpha=0.05, shape="Arrow (2D)", arrow_lengths=(0.4, 0.1), size=0.5))
    assert out["alpha"] == 0.1 and out["display_color"] == (255, 25, 0, 13)  # Detection3DArray's alpha ≥ 0.1
    assert "particle_shape" not in out  # a shape the plugin does not have keeps the default
    assert stack_options(DisplayStyleSpec(shape="Axes")) == {"particle_shape": "Axes"}
    assert out["arrow_lengths"] == (0.4, 0.4) and out["line_width"] == 0.1  # max ≥ min; width ≤ 0.1 m
    DecodeOptions(**out)  # every key is an option


def test_recorded_as_configured(tmp_path_factory: pytest.TempPathFactory) -> None:
    recording = read_recording(stack_recordings(tmp_path_factory)["rviz"])
    particles = recording["/particlecloud"]
    (i,) = [k for k, v in enumerate(particles.temporal["Arrows3D:vectors"]) if v is not None]
    vectors = np.array(particles.temporal["Arrows3D:vectors"][i])
    # shaft L = clamp(w · 0.4 + 0.1, 0.1, 0.5), plus RViz's head (0.3043 L): w 0.5 → 0.3, along yaw 0
    np.testing.assert_allclose(vectors[0], [0.3 * 1.3043, 0, 0], atol=1e-6)
    np.testing.assert_allclose(vectors[1], [0, 0.5 * 1.3043, 0], atol=1e-6)  # w 1, yaw 90°
    assert particles.temporal["Arrows3D:colors"][i] == [0x00B400FF]  # Color 0; 180; 0, Alpha 1
    boxes = recording["/detections_3d"]
    (j,) = [k for k, v in enumerate(boxes.temporal["Boxes3D:centers"]) if v is not None]
    assert boxes.temporal["Boxes3D:fill_mode"][j] == [1]  # MajorWireframe: Only Edge
    assert boxes.temporal["Boxes3D:radii"][j] == [pytest.approx(0.04)]  # Line Width 0.08 m
    assert [c & 0xFF for c in boxes.temporal["Boxes3D:colors"][j]] == [128, 128]  # Alpha 0.5
