"""URDF → immutable model: the tutorial's R2D2 as written, and any URDF with primitives or meshes."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import REPO, SHARED_REFERENCE

from r2d2_viz.robot.model import Box, Cylinder, MeshFile, Sphere, default_urdf_path, load_urdf
from r2d2_viz.robot.synth import random_urdf


@pytest.fixture(scope="module")
def r2d2():
    return load_urdf(default_urdf_path())


def test_shipped_model_is_the_tutorials_byte_for_byte() -> None:
    shipped = default_urdf_path()
    assert "site-packages" in str(shipped) or "dist-packages" in str(shipped)  # package data, not the checkout
    assert shipped.read_bytes() == (REPO / "assets" / "r2d2.urdf").read_bytes()
    if (SHARED_REFERENCE / "r2d2.urdf").exists():
        assert shipped.read_bytes() == (SHARED_REFERENCE / "r2d2.urdf").read_bytes()


def test_links_joints_and_tree(r2d2) -> None:
    assert r2d2.name == "r2d2" and r2d2.root == "axis"
    assert r2d2.links[0].name == "axis"
    assert {j.name: (j.type, j.parent, j.child) for j in r2d2.joints} == {
        "leg1connect": ("fixed", "axis", "leg1"),
        "leg2connect": ("fixed", "axis", "leg2"),
        "tilt": ("revolute", "axis", "body"),
        "swivel": ("continuous", "body", "head"),
        "periscope": ("prismatic", "head", "rod"),
        "boxconnect": ("fixed", "rod", "box"),
    }
    tilt, periscope, swivel = r2d2.joint("tilt"), r2d2.joint("periscope"), r2d2.joint("swivel")
    assert tilt.axis == (0.0, 1.0, 0.0) and (tilt.limit.lower, tilt.limit.upper) == (-0.5, 0.0)
    assert periscope.axis == (0.0, 0.0, 1.0) and np.allclose(periscope.T_parent_joint[:3, 3], [0.12, 0, 0.15])
    assert swivel.limit is None and r2d2.warnings == ()
    with pytest.raises(dataclasses.FrozenInstanceError):
        tilt.name = "x"  # type: ignore[misc]
    with pytest.raises(ValueError):
        tilt.T_parent_joint[0, 3] = 1.0  # read-only array


def test_geometry_and_materials_including_white_defined_once_and_referenced_later(r2d2) -> None:
    by_link = {link.name: link for link in r2d2.links}
    assert by_link["axis"].visuals[0].geometry == Cylinder(radius=0.01, length=0.5)
    assert by_link["leg1"].visuals[0].geometry == Box((0.2, 0.1, 0.8))
    assert by_link["head"].visuals[0].geometry == Sphere(0.4)
    # "white" is defined in leg1's visual; body and head only say <material name="white"/>
    for link in ("leg1", "leg2", "body", "head"):
        assert by_link[link].visuals[0].rgba == (1.0, 1.0, 1.0, 1.0), link
    assert by_link["rod"].visuals[0].rgba == (0.2, 0.2, 0.2, 1.0)  # "gray", defined in axis
    assert by_link["box"].visuals[0].rgba == (0.0, 0.0, 1.0, 1.0)
    assert by_link["body"].visuals[0].T_link_shape[2, 3] == pytest.approx(-0.2)
    assert by_link["body"].collisions[0].T_link_shape[2, 3] == pytest.approx(0.2)
    assert all(len(link.collisions) == 1 for link in r2d2.links)


def test_missing_mesh_is_skipped_with_a_warning_the_rest_loads(tmp_path: Path) -> None:
    trimesh.creation.box(extents=(1, 2, 3)).export(tmp_path / "present.stl")
    (tmp_path / "robot.urdf").write_text(
        '<robot name="m"><link name="base"><visual><geometry><mesh filename="present.stl" scale="2 2 2"/></geometry>'
        '</visual></link><link name="arm"><visual><geometry><mesh filename="meshes/gone.dae"/></geometry></visual>'
        '<visual><geometry><sphere radius="0.1"/></geometry></visual></link>'
        '<joint name="j" type="fixed"><parent link="base"/><child link="arm"/></joint></robot>'
    )
    robot = load_urdf(tmp_path / "robot.urdf")
    base, arm = robot.links
    assert isinstance(base.visuals[0].geometry, MeshFile) and base.visuals[0].geometry.scale == (2.0, 2.0, 2.0)
    assert [type(v.geometry) for v in arm.visuals] == [Sphere]
    assert len(robot.warnings) == 1 and "'arm'" in robot.warnings[0] and "meshes/gone.dae" in robot.warnings[0]


def test_any_urdf_loads_not_just_r2d2(tmp_path: Path) -> None:
    path = tmp_path / "random.urdf"
    path.write_text(random_urdf(60, seed=4))
    robot = load_urdf(path)
    assert len(robot.links) == 60 and len(robot.joints) == 59
    seen = {robot.root}
    for joint in robot.joints:  # topological: every parent is known before its child
        assert joint.parent in seen
        seen.add(joint.child)
