"""URDF shapes → what the viewer draws, without rerun: primitives as triangle meshes, mesh files as asset bytes.

Mesh files reach the viewer as they are where Rerun reads them fully (STL, PLY, GLB, OBJ without ``mtllib``):
:meth:`MeshCache.asset` reads each file once however many links use it. COLLADA (``.dae``), glTF (``.gltf``)
and OBJ files with material libraries are converted once into one GLB that embeds their colours, materials and
textures (Rerun's own COLLADA reader drops textures): COLLADA with pycollada (:mod:`.collada_glb`), the others
with trimesh. The GLB is kept in a disk cache (:class:`DiskCache`) keyed by the file's content, so later runs skip
the conversion.
"""

from __future__ import annotations

import functools
import hashlib
import io
import os
import re
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from r2d2_viz.errors import one_line
from r2d2_viz.meshes import primitives
from r2d2_viz.meshes.collada_glb import collada_to_glb
from r2d2_viz.meshes.disk_cache import DiskCache, sha256
from r2d2_viz.meshes.gltf_write import colour_parts, paint_bare_primitives
from r2d2_viz.robot.model import Box, Cylinder, MeshFile, Shape, Sphere
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.regular_file import NotRegularFileError, read_regular

CYLINDER_SECTIONS = 48
SPHERE_SUBDIVISIONS = 3
CONVERTER_VERSION = 6
"""Bump when the conversion below changes what it writes: old cache entries are then never looked up."""

MAX_MESH_BYTES = 1 << 30
GLB = "model/gltf-binary"
AS_IS = {".stl": "model/stl", ".ply": "application/x-ply", ".glb": GLB, ".obj": "model/obj"}
"""Formats the viewer reads completely from the file's own bytes (OBJ only without a material library)."""
CONVERTED = {".dae": "dae", ".gltf": "gltf", ".obj": "obj"}
"""Formats converted to GLB (their colours live in other files, or Rerun's reader loses them)."""


@dataclass(frozen=True, eq=False)
class TriangleMesh:
    vertices: npt.NDArray[np.float32]  # (V, 3) in the link frame
    normals: npt.NDArray[np.float32]  # (V, 3) unit vertex normals
    triangles: npt.NDArray[np.uint32]  # (F, 3)


@dataclass(frozen=True, eq=False)
class Asset:
    """A mesh file as the viewer gets it: bytes in the shape's own frame, unscaled."""

    data: bytes
    media_type: str
    own_colors: bool
    """Some part of the mesh carries colours, materials or textures (else the viewer draws one default colour)."""
    bare_parts: bool = True
    """Some part of the mesh carries none (all of it when ``own_colors`` is False)."""


class MeshCache:
    """Mesh files of one run: each read (and converted, if need be) once, however many shapes use it.

    ``reads`` counts how often each file was opened, for the tests. ``disk`` keeps conversions between runs:
    True (the default) for :class:`DiskCache` in its default folder, a :class:`DiskCache`, or None to convert
    every run.
    """

    def __init__(self, disk: DiskCache | bool | None = True) -> None:
        self.disk: DiskCache | None = disk if isinstance(disk, DiskCache) else DiskCache() if disk else None
        self.reads: Counter[Path] = Counter()
        self._assets: dict[Path, Asset | str] = {}
        self._painted: dict[tuple[Asset, tuple[float, ...]], Asset] = {}

    def asset(self, path: Path, filename: str | None = None) -> Asset:
        """The viewer's bytes for mesh file ``path``. Raises ``ValueError`` naming ``filename`` when unreadable."""
        key = Path(path).resolve()
        if key not in self._assets:
            try:
                self._assets[key] = self._load(key, Path(path).suffix.lower())  # symlinks: the name's suffix
            except ValueError as exc:
                self._assets[key] = str(exc)
        found = self._assets[key]
        if isinstance(found, str):
            raise ValueError(f"mesh file {filename or str(path)!r} {found}")
        return found

    def painted(self, asset: Asset, rgba: tuple[float, float, float, float]) -> Asset:
        """``asset`` (a GLB) with colour ``rgba`` on its parts that have none of their own; one per colour."""
        key = (asset, rgba)
        if key not in self._painted:
            self._painted[key] = Asset(paint_bare_primitives(asset.data, rgba), GLB, own_colors=True, bare_parts=False)
        return self._painted[key]

    def read(self, path: Path) -> bytes:
        self.reads[path] += 1
        try:
            data = read_regular(path, MAX_MESH_BYTES)  # /dev/zero, a FIFO, a folder: never read
        except (NotRegularFileError, IsADirectoryError):
            raise ValueError("is not a regular file") from None
        except OSError as exc:
            raise ValueError(f"cannot be read: {exc.strerror or exc}") from None
        if len(data) > MAX_MESH_BYTES:
            raise ValueError(f"is larger than {MAX_MESH_BYTES >> 20} MiB")
        return data

    def _load(self, path: Path, suffix: str) -> Asset:
        if suffix not in AS_IS and suffix not in CONVERTED:
            kind = suffix or "(no extension)"
            raise ValueError(f"has an unsupported format {kind!r} (STL, OBJ, DAE, GLB, GLTF, PLY)")
        data = self.read(path)
        if suffix in AS_IS and not (suffix == ".obj" and _obj_material_libraries(data)):
            if suffix == ".glb":
                return _glb_asset(data)
            coloured = _own_colors(suffix, data)
            return Asset(data, AS_IS[suffix], own_colors=coloured, bare_parts=not coloured)
        key = _cache_key(suffix, data)
        if self.disk is not None:
            glb = self.disk.get(key, lambda name: _dependency(path, name))
            if glb is not None:
                return _glb_asset(glb)
        glb, dependencies = convert_to_glb(path, data, suffix)
        if self.disk is not None:
            self.disk.put(key, glb, dependencies)
        return _glb_asset(glb)


# --- conversion ---------------------------------------------------------------------------------------


# trimesh (and scipy behind it) is imported only to convert: a warm run reads the cache and never needs it.


def _recording_resolver(source: Path) -> Any:
    """A trimesh resolver for the textures and material files a mesh names, relative to its folder, that notes
    the sha256 of each file it reads in ``.read``."""
    import trimesh

    class RecordingResolver(trimesh.resolvers.FilePathResolver):
        def __init__(self) -> None:
            # "../textures/x.png" is common in ROS packages and RViz follows it; a URDF can name any mesh file
            # anyway, and what is read only reaches the user's own viewer.
            super().__init__(str(source), allow_anywhere=True)
            self.read: dict[str, str] = {}

        def get(self, name: str) -> bytes:
            data = _read_beside(self, name)
            self.read[name] = sha256(data)
            return data

    return RecordingResolver()


class _Beside:
    """trimesh's ``FilePathResolver(path, allow_anywhere=True)`` lookup, without importing trimesh: checking a
    warm cache entry's textures must not cost trimesh's and SciPy's imports (~1 s)."""

    def __init__(self, source: Path) -> None:
        self.parent = Path(os.path.abspath(source)).parent.resolve()

    def absolute(self, name: str) -> Path:
        return (self.parent / name.strip()).resolve()


def _dependency(path: Path, name: str) -> bytes | None:
    try:
        data = _read_beside(_Beside(path), name)
    except Exception:  # missing, unreadable: the cache entry is stale
        return None
    return data


MAX_DEPENDENCY_BYTES = 512 * 1024 * 1024


def _read_beside(resolver: Any, name: str) -> bytes:
    """What trimesh's ``FilePathResolver.get`` reads for ``name``, but only regular files of sane size: a texture
    named ``/dev/zero`` would otherwise be read forever."""
    name = str(name)
    for candidate in (name.strip(), name.strip().lstrip("/"), os.path.split(name)[-1]):
        try:
            path = Path(resolver.absolute(candidate))
        except ValueError:
            continue
        if path.exists():
            try:
                data: bytes | None = read_regular(path, MAX_DEPENDENCY_BYTES)
            except (NotRegularFileError, IsADirectoryError):
                data = None
            if data is None or len(data) > MAX_DEPENDENCY_BYTES:
                raise FileNotFoundError(f"{name} is not a regular file of at most {MAX_DEPENDENCY_BYTES} bytes")
            return data
    raise FileNotFoundError(name)


def convert_to_glb(path: Path, data: bytes, suffix: str | None = None) -> tuple[bytes, dict[str, str]]:
    """One GLB with the file's colours, materials and textures; and sha256 of each other file it read.

    Raises ``ValueError`` when the file holds no triangles or cannot be parsed.
    """
    file_type = CONVERTED[suffix or path.suffix.lower()]
    if file_type == "dae":  # pycollada alone: no trimesh import on the way to a robot's first frame
        read: dict[str, str] = {}

        def read_beside(name: str) -> bytes:
            found = _read_beside(_Beside(path), name)
            read[name] = sha256(found)
            return found

        return collada_to_glb(data, read_beside), read
    resolver = _recording_resolver(path)
    scene = _load_scene(data, file_type, resolver)
    if not _has_triangles(scene):
        raise ValueError("holds no triangles")
    for geometry in scene.geometry.values():
        # trimesh writes extra vertex attributes (e.g. an OBJ's per-vertex "color") as custom glTF attributes
        # ("_color"), which Rerun's glTF reader refuses outright: "invalid semantic name", nothing drawn.
        attributes = getattr(geometry, "vertex_attributes", None)
        if attributes:
            attributes.clear()
    try:
        glb = scene.export(file_type="glb")
    except Exception as exc:  # trimesh raises many kinds for odd inputs
        raise ValueError(f"cannot be converted: {one_line(exc)}") from None
    return bytes(glb), dict(resolver.read)


def _load_scene(data: bytes, file_type: str, resolver: Any) -> Any:
    import trimesh

    try:
        # process=False: no vertex merging (a third of the conversion time; the GLB comes out the same size)
        return trimesh.load_scene(io.BytesIO(data), file_type=file_type, resolver=resolver, process=False)
    except Exception as exc:  # trimesh raises many kinds for unreadable files
        raise ValueError(f"cannot be read: {one_line(exc)}") from None


def _has_triangles(scene: Any) -> bool:
    import trimesh

    return any(isinstance(g, trimesh.Trimesh) and len(g.faces) > 0 for g in scene.geometry.values())


def _obj_material_libraries(data: bytes) -> bool:
    return re.search(rb"^\s*mtllib\s", data, re.MULTILINE) is not None


def _glb_asset(glb: bytes) -> Asset:
    coloured, bare = colour_parts(glb)
    return Asset(glb, GLB, own_colors=coloured, bare_parts=bare)


def _own_colors(suffix: str, data: bytes) -> bool:
    if suffix == ".ply":
        header = data[: data.find(b"end_header")] if b"end_header" in data[:4096] else b""
        return re.search(rb"property\s+\w+\s+(red|diffuse_red)\b", header) is not None
    if suffix == ".obj":  # vertex colours: "v x y z r g b"
        match = re.search(rb"^v\s+(\S+\s+){5}\S+", data, re.MULTILINE)
        return match is not None
    return False  # STL: geometry only


def _cache_key(suffix: str, data: bytes) -> str:
    """sha256 of the file's bytes and of what shapes the conversion: a new version is a new key."""
    versions = f"{CONVERTER_VERSION}|{_version('trimesh')}|{_version('pycollada')}|{suffix}\0"
    digest = hashlib.sha256(versions.encode())
    digest.update(data)
    return digest.hexdigest()


@functools.cache
def _version(distribution: str) -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(distribution)
    except PackageNotFoundError:
        return "-"


# --- primitives and baked meshes ----------------------------------------------------------------------


def shape_mesh(shape: Shape) -> TriangleMesh:
    """The shape's geometry as a mesh with its ``<origin>`` applied (vertices in the link frame).

    Raises ``ValueError`` when a mesh file cannot be read (the caller skips that shape with a warning).
    """
    geometry = shape.geometry
    if isinstance(geometry, MeshFile):
        vertices, normals, faces = _mesh_file(geometry)
    elif isinstance(geometry, (Box, Cylinder, Sphere)):
        vertices, normals, faces = _primitive(geometry)
    else:  # pragma: no cover - the model only produces the four kinds above
        raise TypeError(f"unknown geometry {geometry!r}")
    R, t = shape.T_link_shape[:3, :3], shape.T_link_shape[:3, 3]
    return TriangleMesh(
        vertices=np.asarray(vertices @ R.T + t, dtype=np.float32),
        normals=np.asarray(normals @ R.T, dtype=np.float32),
        triangles=faces,
    )


Arrays = tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.uint32]]


@functools.lru_cache(maxsize=1024)
def _primitive(geometry: Box | Cylinder | Sphere) -> Arrays:
    """Vertices, unit normals and triangles of a primitive in its own frame; one per distinct size (read-only)."""
    if isinstance(geometry, Box):
        return _frozen(*primitives.box(geometry.size))
    if isinstance(geometry, Cylinder):
        return _frozen(*primitives.cylinder(geometry.radius, geometry.length, CYLINDER_SECTIONS))
    return _frozen(*primitives.sphere(geometry.radius, SPHERE_SUBDIVISIONS))


def _mesh_file(geometry: MeshFile) -> Arrays:
    """A mesh file as one triangle soup (trimesh), scaled: for callers that need vertices, not for drawing."""
    import trimesh

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
    return _frozen(mesh.vertices, mesh.vertex_normals, mesh.faces)


def _frozen(vertices: Any, normals: Any, faces: Any) -> Arrays:
    arrays = (
        np.array(vertices, dtype=np.float64),
        np.array(normals, dtype=np.float64),
        np.array(faces, dtype=np.uint32),
    )
    for a in arrays:
        a.flags.writeable = False
    return arrays


def uri_loader(
    packages: PackageIndex, base_dir: Path, cache: MeshCache | None = None
) -> Callable[[str], tuple[bytes, str] | None]:
    """``uri`` (``package://``, ``file://`` or a path) → the viewer's (bytes, media type) of that mesh file, or None
    when it cannot be found or read: what a MESH_RESOURCE marker draws. Each file is read once."""
    meshes = cache or MeshCache()

    def load(uri: str) -> tuple[bytes, str] | None:
        try:
            path = packages.resolve_uri(uri, base_dir=base_dir)
        except Exception:  # a malformed uri from a message: nothing to draw
            return None
        if path is None:
            return None
        try:
            asset = meshes.asset(path, uri)
        except ValueError:
            return None
        return asset.data, asset.media_type

    return load
