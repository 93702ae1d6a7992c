"""Mass properties as RViz's RobotModel draws them: the lead sphere and the box of equal inertia.

Golden values are worked out here, independently of ``r2d2_viz.robot.inertial``: the URDF is read with the standard
library's ElementTree, origins composed by hand, the eigen decomposition is numpy's general ``eig`` (not the
symmetric ``eigh`` the code uses), and each box must give back the URDF's own tensor (a uniform box of sides a, b,
c has moments m (b² + c²) / 12 …). Pinocchio's inertias are compared only where pinocchio is importable.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

from r2d2_viz.robot.inertial import equivalent_box, inertia_problems, lead_sphere_radius
from r2d2_viz.robot.model import load_urdf, parse_urdf

try:
    ROBOTS = Path(
        str(metadata.distribution("example-robot-data").locate_file("cmeel.prefix/share/example-robot-data/robots"))
    )
except metadata.PackageNotFoundError:  # pragma: no cover - it is in the test extra
    ROBOTS = Path("/nonexistent")

REAL = [
    "talos_data/robots/talos_reduced.urdf",
    "panda_description/urdf/panda.urdf",
    "tiago_description/robots/tiago.urdf",
]
"""TALOS's reduced model rotates 47 of its inertial origins (rpy): the box must turn with them."""


def _rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw),
                              math.sin(yaw))  # fmt: skip
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _by_hand(path: Path) -> dict[str, tuple[float, np.ndarray, np.ndarray, np.ndarray]]:
    """Link → (mass, tensor in the link frame, centre of mass in the link frame, R_link_inertial)."""
    out = {}
    for link in ET.parse(path).getroot().iter("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        origin = inertial.find("origin")
        xyz = [float(v) for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()]
        rpy = [float(v) for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()]
        t = inertial.find("inertia")
        assert t is not None
        i = {k: float(t.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        tensor = np.array(
            [[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]], [i["ixz"], i["iyz"], i["izz"]]]
        )
        mass_el = inertial.find("mass")
        mass = float(mass_el.get("value", "0")) if mass_el is not None else 0.0
        R = _rpy(*rpy)
        out[link.get("name", "")] = (mass, R @ tensor @ R.T, np.array(xyz), R)
    return out


@pytest.mark.parametrize("name", REAL)
def test_inertia_boxes_of_real_robots_match_an_independent_eigen_decomposition(name: str) -> None:
    path = ROBOTS / name
    if not path.is_file():
        pytest.skip("example-robot-data is not installed")
    robot = load_urdf(path)
    expected = _by_hand(path)
    boxes = 0
    for link in robot.links:
        if link.inertial is None:
            continue
        mass, tensor_link, com, _ = expected[link.name]
        box = equivalent_box(link.inertial)
        values, vectors = np.linalg.eig(tensor_link)  # general eig, in the link frame
        values = np.real(values)
        if box is None:  # refused: the hand-made decomposition must find it impossible too
            sides = sorted(values)
            assert mass <= 0 or sides[0] <= 1e-12 * max(abs(sides[-1]), 1e-300) or sides[0] + sides[1] < sides[2]
            continue
        boxes += 1
        a, b, c = box.size
        R = box.T_link_box[:3, :3]
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-9)
        assert np.linalg.det(R) == pytest.approx(1.0)
        # the box's own moments, rotated into the link frame, give back the URDF's tensor
        box_moments = mass / 12 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
        np.testing.assert_allclose(
            R @ np.diag(box_moments) @ R.T, tensor_link, atol=1e-6 * max(1.0, np.abs(tensor_link).max())
        )
        # sides from numpy's eig: sorted sides alike within 1e-6 m; each box axis an eigenvector of the tensor
        i1, i2, i3 = values
        hand = np.sqrt(np.maximum(6 / mass * np.array([i2 + i3 - i1, i3 + i1 - i2, i1 + i2 - i3]), 0))
        np.testing.assert_allclose(sorted(box.size), sorted(hand), atol=1e-6)
        for k in range(3):
            axis = R[:, k]
            assert np.linalg.norm(tensor_link @ axis - box_moments[k] * axis) <= 1e-6 * max(1e-9, np.abs(values).max())
        del vectors
        np.testing.assert_allclose(box.T_link_box[:3, 3], com, atol=1e-12)
    assert boxes >= 10


def test_the_lead_sphere_is_rvizs() -> None:
    """RViz: diameter = 2 ∛(0.75 m / (π · 11340)); 1 kg of lead is a ball of 27.6 mm radius (by hand: 3 / (4π ·
    11340) = 2.1052e-5 m³; 0.027612³ = 2.10524e-5)."""
    assert lead_sphere_radius(1.0) == pytest.approx(0.027612, abs=1e-6)
    assert lead_sphere_radius(8.0) == pytest.approx(2 * lead_sphere_radius(1.0))
    assert lead_sphere_radius(0.0) == 0.0


def test_impossible_inertias_are_one_line_each_and_placeholders_are_quiet() -> None:
    def link(name: str, body: str) -> str:
        return f'<link name="{name}"><inertial>{body}</inertial></link>'

    links = [
        link("good", '<mass value="2"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>'),
        link("negative", '<mass value="2"/><inertia ixx="1" iyy="1" izz="-1" ixy="0" ixz="0" iyz="0"/>'),
        link("triangle", '<mass value="2"/><inertia ixx="0.001" iyy="0.001" izz="0.01" ixy="0" ixz="0" iyz="0"/>'),
        link("massless", '<mass value="0"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>'),
        link("frame", '<mass value="0"/><inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/>'),
    ]
    joints = "".join(
        f'<joint name="j{i}" type="fixed"><parent link="good"/><child link="{n}"/></joint>'
        for i, n in enumerate(["negative", "triangle", "massless", "frame"])
    )
    robot = parse_urdf(f'<robot name="r">{"".join(links)}{joints}</robot>', source="bad.urdf")
    lines = inertia_problems(robot)
    assert [line.split(": ")[1] for line in lines] == ["link 'negative'", "link 'triangle'", "link 'massless'"]
    assert all(line.startswith("bad.urdf: link '") and "\n" not in line for line in lines)
    assert "not positive definite" in lines[0] and "triangle inequality" in lines[1] and "mass 0" in lines[2]
    boxes = {link.name: equivalent_box(link.inertial) for link in robot.links if link.inertial is not None}
    assert boxes["good"] is not None and [k for k, v in boxes.items() if v is None] == list(boxes)[1:]
    # a unit-moment 2 kg box: sides √(6 (1 + 1 − 1) / 2) = √3 each (by hand)
    np.testing.assert_allclose(boxes["good"].size, [math.sqrt(3)] * 3)


def test_against_pinocchio_when_it_is_importable() -> None:
    pinocchio = pytest.importorskip("pinocchio")
    path = ROBOTS / REAL[0]
    model = pinocchio.buildModelFromUrdf(str(path))
    robot = load_urdf(path)
    by_name = {link.name: link for link in robot.links}
    for frame in model.frames:
        link = by_name.get(frame.name)
        if link is None or link.inertial is None or frame.type != pinocchio.FrameType.BODY:
            continue
        inertia = model.inertias[frame.parentJoint]  # merged bodies: compare only a joint's own first body
        if abs(inertia.mass - link.inertial.mass) > 1e-12:
            continue
        R = link.inertial.T_link_inertial[:3, :3]
        np.testing.assert_allclose(R @ link.inertial.inertia @ R.T, frame.placement.rotation @ inertia.inertia
                                   @ frame.placement.rotation.T, atol=1e-6)  # fmt: skip


def test_a_rotated_inertial_origin_turns_the_box() -> None:
    """The tensor is written in the inertial origin's frame (rpy included; RViz 2 drops the rpy). By hand: a 6 kg
    tensor diag(1, 2, 2.5) has sides √(6 (2 + 2.5 − 1) / 6) = √3.5 along its x, √1.5 along y, √0.5 along z; turned
    90° about z, the √3.5 side lies along the link's y and the √1.5 side along its x."""
    text = """<robot name="r"><link name="l"><inertial><origin xyz="0.1 0.2 0.3" rpy="0 0 1.5707963267948966"/>
      <mass value="6"/><inertia ixx="1" iyy="2" izz="2.5" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"""
    (link,) = parse_urdf(text).links
    assert link.inertial is not None
    box = equivalent_box(link.inertial)
    assert box is not None
    R, size = box.T_link_box[:3, :3], box.size
    along = {round(float(s) ** 2, 9): np.abs(R[:, k]) for k, s in enumerate(size)}
    np.testing.assert_allclose(along[3.5], [0, 1, 0], atol=1e-9)
    np.testing.assert_allclose(along[1.5], [1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(along[0.5], [0, 0, 1], atol=1e-9)
    np.testing.assert_allclose(box.T_link_box[:3, 3], [0.1, 0.2, 0.3])
