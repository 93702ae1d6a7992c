"""COLLADA (``.dae``) → one GLB with the file's colours, materials and textures, read with pycollada.

Rerun's own COLLADA reader drops textures, so a ``.dae`` reaches the viewer as a GLB. The mapping is trimesh's
(``trimesh.exchange.dae``, which our tests compare against): each ``<instance_geometry>`` under the scene's node
tree is a glTF node with the product of its ancestors' matrices (a geometry drawn by several nodes is one glTF
mesh); each triangle set (polylists and polygons are triangulated by pycollada) is a primitive whose vertices are
shared as the file's indices share them; a COLLADA effect becomes a metallic-roughness
material (diffuse colour or texture as the base colour, the transparent colour's alpha as its alpha, roughness
``sqrt(2 / (2 + shininess))``, emission). The ``<unit meter>`` scale is applied, as RViz (assimp) does;
``<up_axis>`` is ignored, as RViz does (its mesh loader skips assimp's root node, which holds the up-axis turn).
Done without trimesh, whose import (SciPy, networkx) costs about a second: a cold first frame of a robot with
COLLADA meshes pays only pycollada's parse.
"""

from __future__ import annotations

import io
import re
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

from r2d2_viz.errors import one_line
from r2d2_viz.meshes.gltf_write import GlbBuilder, Material, Primitive

ReadFile = Callable[[str], bytes]
"""Reads a file the COLLADA document names (a texture), relative to the document; raises if it cannot."""


def collada_to_glb(data: bytes, read: ReadFile) -> bytes:
    """The GLB for COLLADA bytes ``data``. Raises ``ValueError`` when they cannot be parsed, hold no triangles, or
    place a vertex at a coordinate that is not a finite number."""
    with np.errstate(all="ignore"):  # NaN and overflow are checked for, not printed as numpy warnings
        return _convert(data, read)


def _convert(data: bytes, read: ReadFile) -> bytes:
    if re.search(rb"<!(DOCTYPE|ENTITY)", data[: max(data.find(b"<COLLADA"), 0)]):
        # pycollada parses with entity expansion on and lxml's size limits off: a DTD could read other files
        # into the mesh or blow up ("billion laughs"). COLLADA needs none.
        raise ValueError("declares a DTD or entities, which COLLADA files do not need; refused")
    document = _parse(data)
    instances = _instances(document)
    triangle_sets = _TriangleSets()
    if not triangle_sets.any_triangles(instances) and b"<instance_material" in data:
        # pycollada drops a whole node when one bound material is broken (anymal's foot: a sampler that
        # names a missing surface); unbind only the broken materials and load again, as RViz shows them.
        document = _parse(_unbind_broken_materials(data))
        instances = _instances(document)
    if not triangle_sets.any_triangles(instances):
        raise ValueError("holds no triangles")
    unit = _unit(document)
    T_scaled = np.diag([unit, unit, unit, 1.0])
    builder = GlbBuilder()
    materials: dict[int, int] = {}  # id(pycollada material) -> glTF material
    meshes: dict[tuple[int, ...], int | None] = {}  # id(geometry), id(bound materials)... -> glTF mesh
    for T_root_node, geometry, bindings in instances:
        bound = [bindings.get(triangles.material) for triangles in triangle_sets(geometry)]
        key = (id(geometry), *(id(material) for material in bound))
        if key not in meshes:  # an instanced geometry is one mesh however many nodes draw it
            primitives = []
            for triangles, material in zip(triangle_sets(geometry), bound, strict=True):
                index = None
                if material is not None:
                    if id(material) not in materials:
                        materials[id(material)] = builder.add_material(_material(material.effect, builder, read))
                    index = materials[id(material)]
                try:
                    primitives.append(_primitive(triangles, index))
                except (IndexError, ValueError) as exc:  # indices past their sources, ragged arrays
                    raise ValueError(f"cannot be read: {one_line(exc)}") from None
            meshes[key] = builder.add_mesh(primitives) if primitives else None
        mesh = meshes[key]
        if mesh is not None:
            T_glb_node = T_scaled @ T_root_node
            if not np.isfinite(T_glb_node).all():
                raise ValueError("cannot be read: a node's matrix is not finite")
            builder.add_node(mesh, T_glb_node)
    return builder.to_bytes()


def _parse(data: bytes) -> Any:
    import collada

    ignore = [
        collada.common.DaeError,
        collada.common.DaeIncompleteError,
        collada.common.DaeMalformedError,
        collada.common.DaeBrokenRefError,
        collada.common.DaeUnsupportedError,
    ]
    try:
        return collada.Collada(io.BytesIO(data), ignore=ignore)
    except Exception as exc:  # pycollada and lxml raise many kinds for unreadable files
        raise ValueError(f"cannot be read: {one_line(exc)}") from None


Instance = tuple[npt.NDArray[np.float64], Any, dict[str, Any]]
"""T_root_node, the pycollada geometry, and its material bindings (symbol -> pycollada material)."""

MAX_DEPTH = 256
"""Node nesting we follow: ``<instance_node>`` can refer to an ancestor, which would otherwise never end."""
MAX_INSTANCES = 100_000
"""Geometry instances we draw: ``<instance_node>`` can also fan out, each level doubling the last."""


def _instances(document: Any) -> list[Instance]:
    """Each ``<instance_geometry>`` in the scene with its accumulated matrix (trimesh's ``_parse_node`` walk)."""
    import collada

    scene = document.scene
    found: list[Instance] = []
    if scene is None:
        return found
    stack: list[tuple[Any, npt.NDArray[np.float64], int]] = [(n, np.eye(4), 0) for n in reversed(scene.nodes)]
    visited = 0
    while stack:
        node, T_root_parent, depth = stack.pop()
        visited += 1
        if visited > MAX_INSTANCES:
            raise ValueError(f"has more than {MAX_INSTANCES} scene nodes (instances of instances?); refused")
        if isinstance(node, collada.scene.GeometryNode):
            bindings = {m.symbol: m.target for m in node.materials if m.target is not None}
            found.append((T_root_parent, node.geometry, bindings))
        elif isinstance(node, collada.scene.Node) and node.children and depth < MAX_DEPTH:
            T_root_node = T_root_parent @ np.asarray(node.matrix, dtype=np.float64)
            stack.extend((child, T_root_node, depth + 1) for child in reversed(node.children))
    return found


class _TriangleSets:
    """Each geometry's triangle sets (polylists and polygons triangulated), computed once per geometry."""

    def __init__(self) -> None:
        self._sets: dict[int, tuple[Any, list[Any]]] = {}  # id -> (geometry, kept alive so ids stay unique)

    def __call__(self, geometry: Any) -> list[Any]:
        import collada

        if id(geometry) not in self._sets:
            sets = []
            for primitive in geometry.primitives:
                if isinstance(primitive, collada.polylist.Polylist):  # also <polygons>
                    primitive = primitive.triangleset()
                if isinstance(primitive, collada.triangleset.TriangleSet) and primitive.vertex is not None:
                    sets.append(primitive)
            self._sets[id(geometry)] = (geometry, sets)
        return self._sets[id(geometry)][1]

    def any_triangles(self, instances: list[Instance]) -> bool:
        return any(len(t.vertex_index) > 0 for _, geometry, _ in instances for t in self(geometry))


def _primitive(triangles: Any, material: int | None) -> Primitive:
    """The triangle set with one vertex per distinct combination of the file's indices (as the file shares them)."""
    columns = [np.asarray(triangles.vertex_index).ravel()]
    has_normals = triangles.normal is not None and triangles.normal_index is not None
    if has_normals:
        columns.append(np.asarray(triangles.normal_index).ravel())
    has_uvs = material is not None and len(triangles.texcoordset) > 0
    uv_column = len(columns)
    if has_uvs:
        columns.append(np.asarray(triangles.texcoord_indexset[0]).ravel())
    sources = triangles.sources
    color_source = None
    if sources.get("COLOR") and len(triangles.index) > 0:
        offset, color_source = sources["COLOR"][0][0], sources["COLOR"][0][4]
        columns.append(np.asarray(triangles.index)[:, :, offset].ravel())
    first, indices = _weld(columns)
    positions = np.asarray(triangles.vertex, dtype=np.float32)[columns[0][first]]
    if not np.isfinite(positions).all():  # NaN, or past float32's range
        raise ValueError("a vertex position is not a finite number")
    uvs = None
    if has_uvs:
        uv = np.asarray(triangles.texcoordset[0], dtype=np.float32)[columns[uv_column][first]]
        uvs = np.nan_to_num(np.column_stack([uv[:, 0], 1.0 - uv[:, 1]]).astype(np.float32), posinf=0, neginf=0)
        # (COLLADA: V up; glTF: V down)
    colors = None
    if color_source is not None:
        values = np.asarray(color_source.data, dtype=np.float32)
        if values.ndim == 2 and values.shape[1] >= 3:
            colors = np.clip(np.nan_to_num(values[columns[-1][first], :4], nan=1.0), 0.0, 1.0)
    if has_normals:
        normals = _unit_rows(np.asarray(triangles.normal, dtype=np.float32)[columns[1][first]])
        return Primitive(positions, indices, normals=normals, uvs=uvs, colors=colors, material=material)
    # no normals in the file: flat shading, a vertex per corner
    positions = positions[indices]
    uvs = None if uvs is None else uvs[indices]
    colors = None if colors is None else colors[indices]
    return Primitive(positions, None, normals=_flat_normals(positions), uvs=uvs, colors=colors, material=material)


def _weld(columns: list[npt.NDArray[Any]]) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.uint32]]:
    """Distinct rows of the index columns: the first corner of each, and each corner's row number."""
    key = np.zeros(len(columns[0]), dtype=np.int64)
    span = 1
    for column in columns:
        column = column.astype(np.int64)
        if len(column) and (column.min() < 0 or span * (int(column.max()) + 1) >= 1 << 62):
            raise ValueError("indices out of range")
        size = int(column.max()) + 1 if len(column) else 1
        key = key * size + column
        span *= size
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    return first, inverse.astype(np.uint32).ravel()


def _unit_rows(vectors: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
    """Each row scaled to length 1; rows of zeros, NaN or infinity become zeros."""
    vectors = np.where(np.isfinite(vectors).all(axis=1, keepdims=True), vectors, np.float32(0))
    lengths = np.linalg.norm(vectors, axis=1, keepdims=True)
    unit: npt.NDArray[np.float32] = np.divide(vectors, lengths, out=np.zeros_like(vectors), where=lengths > 0)
    return unit


def _flat_normals(positions: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
    corners = positions.reshape(-1, 3, 3)
    face = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return _unit_rows(np.repeat(face, 3, axis=0).astype(np.float32))


def _material(effect: Any, builder: GlbBuilder, read: ReadFile) -> Material:
    """trimesh's ``_parse_material`` mapping, with the texture embedded as PNG or JPEG."""
    import collada

    base = (1.0, 1.0, 1.0, 1.0)
    image = None
    if isinstance(effect.diffuse, collada.material.Map):
        image = _texture(effect.diffuse, builder, read)
    elif effect.diffuse is not None:
        base = _rgba(effect.diffuse)
    if effect.transparent is not None and not isinstance(effect.transparent, collada.material.Map):
        base = (*base[:3], float(_rgba(effect.transparent)[3]))
    emissive = (0.0, 0.0, 0.0)
    if effect.emission is not None and not isinstance(effect.emission, collada.material.Map):
        emissive = _rgba(effect.emission)[:3]
    roughness = 1.0
    if effect.shininess is not None and not isinstance(effect.shininess, collada.material.Map):
        try:
            roughness = float(np.sqrt(2.0 / (2.0 + max(float(effect.shininess), 0.0))))
        except (TypeError, ValueError):
            roughness = 1.0
    return Material(base_color=base, roughness=roughness, emissive=emissive, image=image)


def _rgba(value: Any) -> tuple[float, float, float, float]:
    v = [float(x) for x in value][:4]
    v += [1.0] * (4 - len(v))
    r, g, b, a = (float(np.clip(x, 0.0, 1.0)) if np.isfinite(x) else 1.0 for x in v)
    return (r, g, b, a)


def _texture(diffuse: Any, builder: GlbBuilder, read: ReadFile) -> int | None:
    """The base-colour texture of a ``<texture>`` reference, or None when its image cannot be read."""
    try:
        name = diffuse.sampler.surface.image.path
        data = read(name)
    except Exception:  # a broken reference or a missing file: the material stays white, as in trimesh
        return None
    if data.startswith(b"\x89PNG\r\n\x1a\n"):
        return builder.add_image(data, "image/png")
    if data.startswith(b"\xff\xd8\xff"):
        return builder.add_image(data, "image/jpeg")
    png = _as_png(data)  # TGA, BMP, …: glTF embeds only PNG and JPEG
    return builder.add_image(png, "image/png") if png is not None else None


def _as_png(data: bytes) -> bytes | None:
    from PIL import Image

    try:
        with Image.open(io.BytesIO(data)) as image:
            out = io.BytesIO()
            image.save(out, format="PNG")
            return out.getvalue()
    except Exception:  # unreadable, or over Pillow's decompression-bomb limit
        return None


def _unit(document: Any) -> float:
    """``<unit meter>``: the scale to metres (1 when absent or not a positive finite number)."""
    value = getattr(document.assetInfo, "unitmeter", None)
    try:
        unit = float(value) if value is not None else 1.0
    except (TypeError, ValueError):
        return 1.0
    return unit if np.isfinite(unit) and unit > 0 else 1.0


def _unbind_broken_materials(data: bytes) -> bytes:
    """The COLLADA document without the ``<instance_material>`` bindings pycollada cannot resolve."""
    import collada
    from lxml import etree

    ignore = [collada.common.DaeBrokenRefError, collada.common.DaeUnsupportedError, collada.common.DaeError]
    try:
        loaded = collada.Collada(io.BytesIO(data), ignore=ignore)
    except Exception:
        return data
    good = {material.id for material in loaded.materials}
    root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=True))
    for element in root.iter("{*}instance_material"):
        if str(element.get("target", "")).lstrip("#") not in good:
            parent = element.getparent()
            if parent is not None:
                parent.remove(element)
    result: bytes = etree.tostring(root)
    return result
