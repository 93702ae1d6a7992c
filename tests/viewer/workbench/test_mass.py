"""Mass properties and link axes in a recording: ``--mass --inertia --link-axes`` and an RViz config's RobotModel
options, read back with Rerun's reader. Values by hand from the URDF below."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from conftest import REPO, cli
from rrd import read_recording

# 'base' (8 kg, moments 1, 2, 2.5 in a frame turned 90° about z), 'arm' (impossible: 0.001 + 0.001 < 0.01),
# 'tip' (a frame: no inertial)
URDF = """<robot name="m">
<link name="base"><inertial><origin xyz="0.1 0 0.2" rpy="0 0 1.5707963267948966"/><mass value="8"/>
  <inertia ixx="1" iyy="2" izz="2.5" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="arm"><inertial><mass value="1"/><inertia ixx="0.001" iyy="0.001" izz="0.01" ixy="0" ixz="0" iyz="0"/>
  </inertial></link>
<link name="tip"/>
<joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="k" type="fixed"><parent link="arm"/><child link="tip"/></joint>
</robot>"""

RVIZ = """Visualization Manager:
  Class: ""
  Displays:
    - Class: rviz_default_plugins/RobotModel
      Enabled: true
      Name: RobotModel
      Links:
        All Links Enabled: true
        tip:
          Show Axes: true
          Value: true
        base:
          Show Axes: false
          Value: true
      Mass Properties:
        Inertia: false
        Mass: true
      Value: true
  Global Options:
    Fixed Frame: base
"""


def _urdf(tmp_path: Path) -> Path:
    path = tmp_path / "m.urdf"
    path.write_text(URDF)
    return path


def test_flags_log_the_lead_ball_the_box_and_every_links_axes(tmp_path: Path) -> None:
    out = tmp_path / "m.rrd"
    result = cli("--urdf", str(_urdf(tmp_path)), "--mass", "--inertia", "--link-axes", "--save", str(out),
                 "--duration", "0.2")  # fmt: skip
    assert result.returncode == 0, result.stderr
    triangle = "m.urdf: link 'arm': <inertial>: principal moments 0.001, 0.001, 0.01 kg·m² violate the triangle"
    assert sum(triangle in line for line in result.stderr.splitlines()) == 1, result.stderr
    rec = read_recording(out)
    ball = rec["/robot/mass/base"].static
    radius = (0.75 * 8 / (math.pi * 11340)) ** (1 / 3)  # RViz: diameter = 2 ∛(0.75 m / (π ρ_lead))
    np.testing.assert_allclose(ball["Ellipsoids3D:half_sizes"][-1], [[radius] * 3], rtol=1e-6)
    np.testing.assert_allclose(ball["Ellipsoids3D:centers"][-1], [[0.1, 0, 0.2]], rtol=1e-6)
    assert ball["CoordinateFrame:frame"][-1] == ["base"]
    box = rec["/robot/inertia/base"].static
    # gz-math's EquivalentBox: x = √(6 (I₂ + I₃ − I₁) / m) …: √(6·3.5/8), √(6·1.5/8), √(6·0.5/8), along the
    # principal axes, i.e. the inertial frame's x, y, z, turned 90° about z: xyzw (0, 0, sin 45°, cos 45°)
    sides = [math.sqrt(6 * 3.5 / 8), math.sqrt(6 * 1.5 / 8), math.sqrt(6 * 0.5 / 8)]
    np.testing.assert_allclose(np.abs(box["Boxes3D:half_sizes"][-1]), [np.array(sides) / 2], rtol=1e-6)
    np.testing.assert_allclose(box["Boxes3D:centers"][-1], [[0.1, 0, 0.2]], rtol=1e-6)
    h = math.sqrt(0.5)
    np.testing.assert_allclose(np.abs(box["Boxes3D:quaternions"][-1]), [[0, 0, h, h]], atol=1e-6)
    assert "RerunWarning" not in result.stderr, result.stderr
    assert "/robot/mass/arm" in rec and "/robot/inertia/arm" not in rec  # no real box: RViz shows none either
    assert "/robot/mass/tip" not in rec
    assert {e for e in rec if e.startswith("/robot/axes/")} == {
        "/robot/axes/base",
        "/robot/axes/arm",
        "/robot/axes/tip",
    }
    assert rec["/robot/axes/tip"].static["CoordinateFrame:frame"][-1] == ["tip"]


def test_off_by_default(tmp_path: Path) -> None:
    out = tmp_path / "plain.rrd"
    result = cli("--urdf", str(_urdf(tmp_path)), "--save", str(out), "--duration", "0.2")
    assert result.returncode == 0, result.stderr
    assert "triangle" not in result.stderr
    assert not any(e.startswith(("/robot/mass", "/robot/inertia", "/robot/axes")) for e in read_recording(out))


def test_an_rviz_configs_mass_properties_and_show_axes(tmp_path: Path) -> None:
    config = tmp_path / "m.rviz"
    config.write_text(RVIZ)
    out = tmp_path / "rviz.rrd"
    result = cli("--urdf", str(_urdf(tmp_path)), "--rviz", str(config), "--save", str(out), "--duration", "0.2")
    assert result.returncode == 0, result.stderr
    rec = read_recording(out)
    assert {e for e in rec if e.startswith(("/robot/mass", "/robot/inertia", "/robot/axes"))} == {
        "/robot/mass/base",
        "/robot/mass/arm",
        "/robot/axes/tip",
    }
    assert "triangle" not in result.stderr  # Inertia is off: its problems are not asked for


def test_a_robot_with_no_inertial_says_there_is_nothing_to_show(tmp_path: Path) -> None:
    # examples/arm6.urdf has no <inertial>: --mass used to show nothing and say nothing
    arm = REPO / "examples" / "arm6.urdf"
    assert "<inertial" not in arm.read_text()
    for flag in ("--mass", "--inertia"):
        result = cli("--urdf", str(arm), flag, "--save", str(tmp_path / "a.rrd"), "--duration", "0.2")
        assert result.returncode == 0, result.stderr
        lines = [x for x in result.stderr.splitlines() if "no link has" in x]
        assert len(lines) == 1 and lines[0].endswith("arm6.urdf: no link has an inertial: nothing to show"), lines
    result = cli("--urdf", str(_urdf(tmp_path)), "--mass", "--save", str(tmp_path / "m.rrd"), "--duration", "0.2")
    assert "no link has an inertial" not in result.stderr  # a robot with some says nothing of the kind
