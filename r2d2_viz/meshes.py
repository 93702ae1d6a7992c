"""URDF shapes → triangle meshes (via trimesh), in their link's frame. No rerun import."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import trimesh

from .model import Box, Cylinder, MeshFile, Shape, Sphere

CYLINDER_SECTIONS = 48
SPHERE_SUBDIVISIONS = 3


@dataclass(frozen=True, eq=False)
class TriangleMesh:
    vertices: npt.NDArray[np.float32]  # (V, 3) in the link frame
    normals: npt.NDArray[np.float32]  # (V, 3) unit vertex normals
    triangles: npt.NDArray[np.uint32]  # (F, 3)


def shape_mesh(shape: Shape) -> TriangleMesh:
    """The shape's geometry as a mesh with its ``<origin>`` applied (vertices in the link frame).

    Raises ``ValueError`` when a mesh file cannot be read (the caller skips that shape with a warning).
    """
    geometry = shape.geometry
    if isinstance(geometry, Box):
        mesh = trimesh.creation.box(extents=geometry.size)
    elif isinstance(geometry, Cylinder):
        mesh = trimesh.creation.cylinder(radius=geometry.radius, height=geometry.length, sections=CYLINDER_SECTIONS)
    elif isinstance(geometry, Sphere):
        mesh = trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=geometry.radius)
    elif isinstance(geometry, MeshFile):
        if geometry.path is None:
            raise ValueError(f"mesh file {geometry.filename!r} not found")
        try:
            loaded = trimesh.load(geometry.path, force="mesh")
        except Exception as exc:  # trimesh raises many kinds for unreadable files
            raise ValueError(f"mesh file {geometry.filename!r} cannot be read: {exc}") from None
        if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
            raise ValueError(f"mesh file {geometry.filename!r} holds no triangles")
        mesh = loaded.copy()
        mesh.apply_scale(geometry.scale)  # type: ignore[no-untyped-call]
    else:  # pragma: no cover - the model only produces the four kinds above
        raise TypeError(f"unknown geometry {geometry!r}")
    if isinstance(geometry, (Box, Cylinder)):
        # Flat faces keep sharp edges: one vertex per face corner. Cylinder walls get radial normals.
        mesh.unmerge_vertices()
        normals = np.repeat(mesh.face_normals, 3, axis=0)[np.argsort(mesh.faces.reshape(-1))]
        if isinstance(geometry, Cylinder):
            wall = np.abs(normals[:, 2]) < 0.5
            radial = mesh.vertices[wall] * [1.0, 1.0, 0.0]
            normals[wall] = radial / np.linalg.norm(radial, axis=1, keepdims=True)
    else:
        normals = np.asarray(mesh.vertex_normals)
    R, t = shape.T_link_shape[:3, :3], shape.T_link_shape[:3, 3]
    vertices = mesh.vertices @ R.T + t
    normals = normals @ R.T
    return TriangleMesh(
        vertices=np.asarray(vertices, dtype=np.float32),
        normals=np.asarray(normals, dtype=np.float32),
        triangles=np.asarray(mesh.faces, dtype=np.uint32),
    )
