"""One URDF ``<visual>`` / ``<collision>`` shape → the Rerun archetypes that draw it, logged static.

Every shape entity is drawn in its link's named frame (``CoordinateFrame``). Mesh files go to the viewer as
``Asset3D`` bytes (see :mod:`r2d2_viz.meshes.assets`), placed by an ``InstancePoses3D`` on the same entity that carries
the shape's ``<origin>`` and the mesh ``scale`` (as Rerun's own URDF loader does), so nothing is re-encoded.
Boxes, cylinders and spheres are small ``Mesh3D`` with their origin baked in.

Colours follow RViz's rule (``RobotLink::assignMaterialsToEntities`` in RViz 1 and 2): a part of a mesh that has
a material of its own keeps it, and the URDF colour (``<material>``) paints only the parts that have none — a
whole STL, or a COLLADA/OBJ/glTF part without a material. A mesh with no colour anywhere gets the URDF colour as
its ``albedo_factor``; a mesh with some bare parts gets those parts a material of that colour in its GLB; without
a URDF colour, RViz-like light grey. Collision shapes are all one translucent orange.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable

import numpy as np
import pyarrow as pa
import rerun as rr

from r2d2_viz.kinematics.transforms import matrix_to_quat
from r2d2_viz.meshes.assets import Asset, MeshCache, shape_mesh
from r2d2_viz.robot.model import MeshFile, Rgba, Shape

BLOB_TYPE = pa.list_(pa.field("item", pa.uint8(), nullable=False))
"""Arrow type of ``rerun.components.Blob``: an array of exactly this type is taken as it is, without a copy."""
COLLISION_COLOR = (255, 140, 0, 160)
DEFAULT_VISUAL_COLOR = (204, 204, 204, 255)


def rgba8(rgba: Rgba | None, default: tuple[int, ...]) -> tuple[int, ...]:
    if rgba is None:
        return default
    return tuple(round(min(max(c, 0.0), 1.0) * 255) for c in rgba)


def linear_rgba(rgba: tuple[int, ...]) -> tuple[float, float, float, float]:
    """An 8-bit sRGB colour (as Rerun reads ``albedo_factor``) as glTF's linear ``baseColorFactor``, so a painted
    part looks the same as an asset coloured through its albedo factor."""
    r, g, b = (((c / 255 + 0.055) / 1.055) ** 2.4 if c / 255 > 0.04045 else c / 255 / 12.92 for c in rgba[:3])
    return (r, g, b, rgba[3] / 255)


def shape_archetypes(link: str, shape: Shape, *, visual: bool, cache: MeshCache) -> list[rr.AsComponents]:
    """What to log on the shape's entity. Raises ``ValueError`` (naming the mesh file) when it cannot be drawn."""
    geometry = shape.geometry
    if not isinstance(geometry, MeshFile):
        mesh = shape_mesh(shape)
        color = rgba8(shape.rgba, DEFAULT_VISUAL_COLOR) if visual else COLLISION_COLOR
        return [
            rr.CoordinateFrame(link),
            rr.Mesh3D(
                vertex_positions=mesh.vertices,
                vertex_normals=mesh.normals,
                triangle_indices=mesh.triangles,
                albedo_factor=color,
            ),
        ]
    if geometry.path is None:
        raise ValueError(f"mesh file {geometry.filename!r} not found")
    asset = cache.asset(geometry.path, geometry.filename)
    factor: tuple[int, ...] | None = None
    colour = rgba8(shape.rgba, DEFAULT_VISUAL_COLOR)
    if not visual:
        factor = COLLISION_COLOR
    elif not asset.own_colors:
        factor = colour
    elif asset.bare_parts:
        asset = cache.painted(asset, linear_rgba(colour))
    T = np.asarray(shape.T_link_shape, dtype=np.float64)
    return [
        rr.CoordinateFrame(link),
        # a prebuilt BlobBatch is taken as it is (rerun.encodings.BlobExt), though not in the type hints
        rr.Asset3D.from_fields(blob=_blob(asset), media_type=asset.media_type, albedo_factor=factor),  # type: ignore[arg-type]
        rr.InstancePoses3D(
            translations=[T[:3, 3]],
            quaternions=matrix_to_quat(T[:3, :3]),  # xyzw
            scales=[geometry.scale],
        ),
    ]


_BLOBS: weakref.WeakKeyDictionary[Asset, rr.components.BlobBatch] = weakref.WeakKeyDictionary()
"""Each asset's blob while the asset lives (its run's :class:`MeshCache`): an ``lru_cache`` of 256 would keep a
``--watch`` reload's assets, and their bytes, after the robot that drew them is gone."""


def _blob(asset: Asset) -> rr.components.BlobBatch:
    """The asset's bytes as one Arrow blob, built once per file and without copying them (Rerun's own conversion
    copies every byte through numpy, every time a shape logs the file)."""
    if (found := _BLOBS.get(asset)) is not None:
        return found
    values = pa.Array.from_buffers(pa.uint8(), len(asset.data), [None, pa.py_buffer(asset.data)])
    offsets = pa.array([0, len(asset.data)], type=pa.int32())
    blob = _BLOBS[asset] = rr.components.BlobBatch(pa.ListArray.from_arrays(offsets, values, type=BLOB_TYPE))
    return blob


def log_shape(
    rec: rr.RecordingStream,
    entity: str,
    link: str,
    shape: Shape,
    *,
    visual: bool,
    cache: MeshCache,
    warn: Callable[[str], None],
) -> None:
    """Log one shape static on ``entity``; a shape that cannot be drawn is skipped with one ``warn`` line."""
    try:
        archetypes = shape_archetypes(link, shape, visual=visual, cache=cache)
    except ValueError as exc:
        warn(f"link {link!r}: {exc}; shape skipped")
        return
    rec.log(entity, *archetypes, static=True)
