"""URDF boxes, cylinders and spheres as triangle meshes with unit normals, in numpy alone (no trimesh at start-up).

All in the shape's own frame, centred on its origin (URDF convention: a cylinder along z). Triangles wind
counter-clockwise seen from outside. Flat faces keep sharp edges (a vertex per face corner); a cylinder's wall has
radial normals; a sphere is an icosphere with normals along the radius.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
U32 = npt.NDArray[np.uint32]


def box(size: tuple[float, float, float]) -> tuple[F64, F64, U32]:
    """24 vertices (4 per face), 12 triangles."""
    half = np.abs(np.asarray(size, dtype=np.float64)) / 2
    vertices: list[F64] = []
    normals: list[F64] = []
    triangles: list[tuple[int, int, int]] = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3  # (u, v, axis) is right-handed
        for sign in (1.0, -1.0):
            n = np.zeros(3)
            n[axis] = sign
            corners = []
            for cu, cv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = np.zeros(3)
                p[axis], p[u], p[v] = sign * half[axis], cu * half[u], cv * half[v]
                corners.append(p)
            base = len(vertices)
            vertices.extend(corners)
            normals.extend([n] * 4)
            quad = [(0, 1, 2), (0, 2, 3)] if sign > 0 else [(0, 2, 1), (0, 3, 2)]
            triangles.extend([(base + a, base + b, base + c) for a, b, c in quad])
    return np.array(vertices), np.array(normals), np.array(triangles, dtype=np.uint32)


def cylinder(radius: float, length: float, sections: int) -> tuple[F64, F64, U32]:
    """Wall (two rings, radial normals) and two caps (a centre and a ring each, normals ±z)."""
    angles = np.linspace(0.0, 2 * np.pi, sections, endpoint=False)
    ring = np.stack([np.cos(angles), np.sin(angles), np.zeros(sections)], axis=1)
    h = length / 2
    i = np.arange(sections)
    j = (i + 1) % sections
    bottom, top = ring * radius + [0, 0, -h], ring * radius + [0, 0, h]
    wall_v = np.concatenate([bottom, top])
    wall_n = np.concatenate([ring, ring])
    wall_t = np.concatenate([np.stack([i, j, sections + j], 1), np.stack([i, sections + j, sections + i], 1)])
    vertices, normals, triangles = [wall_v], [wall_n], [wall_t]
    offset = len(wall_v)
    for z, sign in ((h, 1.0), (-h, -1.0)):
        cap = np.concatenate([[[0.0, 0.0, z]], ring * radius + [0, 0, z]])
        centre = np.zeros(sections, dtype=np.int64)
        faces = np.stack([centre, 1 + i, 1 + j], 1) if sign > 0 else np.stack([centre, 1 + j, 1 + i], 1)
        vertices.append(cap)
        normals.append(np.tile([0.0, 0.0, sign], (sections + 1, 1)))
        triangles.append(faces + offset)
        offset += sections + 1
    return np.concatenate(vertices), np.concatenate(normals), np.concatenate(triangles).astype(np.uint32)


def sphere(radius: float, subdivisions: int) -> tuple[F64, F64, U32]:
    """An icosahedron split ``subdivisions`` times (each triangle into four), pushed onto the sphere."""
    unit, triangles = _icosphere(subdivisions)
    return unit * radius, unit.copy(), triangles


def _icosphere(subdivisions: int) -> tuple[F64, U32]:
    t = (1 + 5**0.5) / 2
    points: list[tuple[float, float, float]] = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t)]
    points += [(0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    vertices = [np.array(p, dtype=np.float64) / np.linalg.norm(p) for p in points]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2)]
    faces += [(10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5)]
    faces += [(2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(subdivisions):
        middle: dict[tuple[int, int], int] = {}
        split = []
        for a, b, c in faces:
            ab, bc, ca = (_midpoint(vertices, middle, x, y) for x, y in ((a, b), (b, c), (c, a)))
            split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = split
    return np.array(vertices), np.array(faces, dtype=np.uint32)


def _midpoint(vertices: list[F64], middle: dict[tuple[int, int], int], a: int, b: int) -> int:
    """Index of the vertex halfway between ``a`` and ``b`` on the unit sphere (made once per edge)."""
    key = (min(a, b), max(a, b))
    if key not in middle:
        p = vertices[a] + vertices[b]
        vertices.append(p / np.linalg.norm(p))
        middle[key] = len(vertices) - 1
    return middle[key]
