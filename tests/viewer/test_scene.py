"""The static scene of a small hand-written robot, read back: values worked out by hand from its URDF."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from rrd import read_recording

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.viewer.notices import Notices
from r2d2_viz.viewer.scene import log_scene

# base → (fixed, 0.2 m up, turned 90° about z) → mast → (revolute at the mast's origin) → head
# base → (prismatic, 0.1 m along x) → slider
URDF = """<robot name="r">
<link name="base"><visual><geometry><box size="0.2 0.2 0.1"/></geometry>
  <material name="red"><color rgba="1 0 0 1"/></material></visual></link>
<link name="mast"/><link name="head"/><link name="slider"/>
<joint name="fix" type="fixed"><parent link="base"/><child link="mast"/>
  <origin xyz="0 0 0.2" rpy="0 0 1.5707963267948966"/></joint>
<joint name="pan" type="revolute"><parent link="mast"/><child link="head"/><axis xyz="0 0 1"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="slide" type="prismatic"><parent link="base"/><child link="slider"/><origin xyz="0.1 0 0"/>
  <axis xyz="1 0 0"/><limit lower="0" upper="1" effort="1" velocity="1"/></joint>
</robot>"""


@pytest.mark.parametrize("root_is_static", [True, False])
def test_static_transforms_arrows_axes_and_shapes(tmp_path: Path, root_is_static: bool) -> None:
    path = tmp_path / "r.urdf"
    path.write_text(URDF)
    tree = compile_tree(load_urdf(path))
    out = tmp_path / "s.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    log_scene(
        rec,
        tree,
        Notices(rec, warn=lambda _: None),
        fixed_frame="odom",
        root_is_static=root_is_static,
        axis_length=0.25,
        show_names=True,
    )
    rec.flush()
    rec.disconnect()
    recording = read_recording(out)
    mast = recording["/tf_static/mast"].static
    assert mast["Transform3D:parent_frame"][-1] == ["base"]
    assert np.allclose(mast["Transform3D:translation"][-1][0], [0, 0, 0.2])
    s = math.sqrt(0.5)  # 90° about z: xyzw (0, 0, sin 45°, cos 45°)
    assert np.allclose(np.abs(mast["Transform3D:quaternion"][-1][0]), [0, 0, s, s], atol=1e-7)
    assert ("/tf_static/base" in recording) == root_is_static  # odom → base, unless the source moves the root
    # arrows: mast (0.2 m from base) static; head sits on the mast's origin (no arrow); the slider moves (on /tf)
    assert np.allclose(recording["/tf_arrows/mast"].static["Arrows3D:vectors"][-1][0], [0, 0, -0.2])
    assert "/tf_arrows/head" not in recording and "/tf_arrows/slider" not in recording
    for frame in ("odom", "base", "mast", "head", "slider"):
        axes = recording[f"/tf_axes/{frame}"].static
        assert axes["TransformAxes3D:axis_length"][-1] == [pytest.approx(0.25)]
        assert axes["TransformAxes3D:show_frame"][-1] == [True]
    base = recording["/robot/visual/base/0"].static
    assert base["CoordinateFrame:frame"][-1] == ["base"] and base["Mesh3D:albedo_factor"][-1] == [0xFF0000FF]
