"""Primitives in numpy, checked against geometry worked out by hand and against trimesh (an independent library).

For each: every triangle winds counter-clockwise seen from outside (its normal points away from the centre), the
surface is closed (trimesh's ``is_watertight`` after merging coincident vertices), volume and area match the
closed forms (a polygonal cylinder / icosphere by their own formulas), and normals are unit and outward.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from r2d2_viz.meshes import primitives


def _check_closed_outward(vertices: np.ndarray, normals: np.ndarray, triangles: np.ndarray) -> trimesh.Trimesh:
    assert triangles.dtype == np.uint32 and triangles.max() < len(vertices) == len(normals)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    corners = vertices[triangles]
    face_normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert (np.einsum("ij,ij->i", face_normals, corners.mean(axis=1)) > 0).all()  # outward: centre at origin
    # vertex normals agree with the faces they belong to (sharp or smooth, never inside out)
    assert (np.einsum("ij,ij->i", normals[triangles[:, 0]], face_normals) > 0).all()
    mesh = trimesh.Trimesh(vertices, triangles, process=True)  # merges coincident vertices
    assert mesh.is_watertight and mesh.is_winding_consistent
    return mesh


def test_box() -> None:
    v, n, t = primitives.box((0.6, 0.1, 0.2))  # the tutorial's box
    assert len(v) == 24 and len(t) == 12
    assert np.allclose(v.min(axis=0), [-0.3, -0.05, -0.1]) and np.allclose(v.max(axis=0), [0.3, 0.05, 0.1])
    mesh = _check_closed_outward(v, n, t)
    assert mesh.volume == pytest.approx(0.6 * 0.1 * 0.2)
    assert mesh.area == pytest.approx(2 * (0.6 * 0.1 + 0.6 * 0.2 + 0.1 * 0.2))
    assert set(map(tuple, np.abs(n).astype(int))) == {(1, 0, 0), (0, 1, 0), (0, 0, 1)}  # flat faces


@pytest.mark.parametrize("sections", [3, 48])
def test_cylinder(sections: int) -> None:
    r, length = 0.2, 0.6
    v, n, t = primitives.cylinder(r, length, sections)
    mesh = _check_closed_outward(v, n, t)
    assert np.allclose(v[:, 2].min(), -0.3) and np.allclose(v[:, 2].max(), 0.3)
    radial = np.linalg.norm(v[:, :2], axis=1)
    assert np.allclose(radial[radial > 1e-12], r)
    polygon = 0.5 * sections * r * r * np.sin(2 * np.pi / sections)  # area of the inscribed regular polygon
    assert mesh.volume == pytest.approx(polygon * length)
    wall = np.abs(n[:, 2]) < 0.5
    assert np.allclose(n[wall, :2], v[wall, :2] / r)  # radial normals on the wall
    # the same cylinder from trimesh: same volume
    assert mesh.volume == pytest.approx(trimesh.creation.cylinder(radius=r, height=length, sections=sections).volume)


def test_sphere_is_trimesh_icosphere() -> None:
    v, n, t = primitives.sphere(0.2, 3)
    mesh = _check_closed_outward(v, n, t)
    reference = trimesh.creation.icosphere(subdivisions=3, radius=0.2)
    assert (len(v), len(t)) == (len(reference.vertices), len(reference.faces)) == (642, 1280)
    assert np.allclose(np.linalg.norm(v, axis=1), 0.2)
    assert np.allclose(n, v / 0.2)
    assert mesh.volume == pytest.approx(reference.volume, rel=1e-9)
    assert mesh.area == pytest.approx(reference.area, rel=1e-9)
