"""A minimal glTF 2.0 binary (GLB) writer: triangle meshes, materials, embedded images, nodes with matrices; and
what the viewer's colour rule needs to know of any GLB: which primitives carry a colour of their own, and the
same GLB with a material given to those that do not (:func:`paint_bare_primitives`).

Only what a converted mesh file needs, written straight from numpy arrays (no trimesh, whose import costs
about a second). The layout follows the glTF 2.0 specification: a 12-byte header, a JSON chunk padded with
spaces and a BIN chunk padded with zeros, both to 4 bytes; one buffer, one buffer view per array.
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

FLOAT = 5126
UNSIGNED_INT = 5125
ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963
TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}


@dataclass(frozen=True)
class Material:
    """A glTF metallic-roughness material: ``base_color`` RGBA in 0..1, an optional base-colour image."""

    base_color: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    roughness: float = 1.0
    emissive: tuple[float, float, float] = (0.0, 0.0, 0.0)
    image: int | None = None
    """Index returned by :meth:`GlbBuilder.add_image`."""


@dataclass(frozen=True, eq=False)
class Primitive:
    """One triangle list: ``positions`` (V, 3), optional per-vertex data, ``indices`` (3F,) into the vertices
    (None: a vertex per corner, V = 3F)."""

    positions: npt.NDArray[np.float32]
    indices: npt.NDArray[np.uint32] | None = None
    normals: npt.NDArray[np.float32] | None = None
    uvs: npt.NDArray[np.float32] | None = None
    """glTF convention: (0, 0) is the image's top-left corner."""
    colors: npt.NDArray[np.float32] | None = None
    """RGB or RGBA in 0..1."""
    material: int | None = None


@dataclass
class GlbBuilder:
    """Collects arrays and JSON, then :meth:`to_bytes` writes one GLB."""

    _blob: bytearray = field(default_factory=bytearray)
    _doc: dict[str, list[Any]] = field(
        default_factory=lambda: {
            k: [] for k in ("bufferViews", "accessors", "images", "textures", "materials", "meshes", "nodes")
        }
    )

    def _view(self, data: bytes, target: int | None = None) -> int:
        self._blob.extend(b"\0" * (-len(self._blob) % 4))
        view: dict[str, Any] = {"buffer": 0, "byteOffset": len(self._blob), "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self._blob.extend(data)
        self._doc["bufferViews"].append(view)
        return len(self._doc["bufferViews"]) - 1

    def _accessor(self, array: npt.NDArray[Any], *, component: int, target: int, bounds: bool = False) -> int:
        width = 1 if array.ndim == 1 else array.shape[1]
        dtype = np.float32 if component == FLOAT else np.uint32
        data = np.ascontiguousarray(array, dtype=dtype)
        accessor: dict[str, Any] = {
            "bufferView": self._view(data.tobytes(), target),
            "componentType": component,
            "count": len(data),
            "type": TYPES[width],
        }
        if bounds:  # required for POSITION
            accessor["min"] = [float(v) for v in data.min(axis=0)]
            accessor["max"] = [float(v) for v in data.max(axis=0)]
        self._doc["accessors"].append(accessor)
        return len(self._doc["accessors"]) - 1

    def add_image(self, data: bytes, mime_type: str) -> int:
        """An embedded PNG or JPEG image; returns its texture index."""
        self._doc["images"].append({"bufferView": self._view(data), "mimeType": mime_type})
        self._doc["textures"].append({"source": len(self._doc["images"]) - 1})
        return len(self._doc["textures"]) - 1

    def add_material(self, material: Material) -> int:
        pbr: dict[str, Any] = {
            "baseColorFactor": [float(v) for v in material.base_color],
            "metallicFactor": 0.0,
            "roughnessFactor": float(material.roughness),
        }
        if material.image is not None:
            pbr["baseColorTexture"] = {"index": material.image}
        entry: dict[str, Any] = {"pbrMetallicRoughness": pbr}
        if any(material.emissive):
            entry["emissiveFactor"] = [float(v) for v in material.emissive]
        self._doc["materials"].append(entry)
        return len(self._doc["materials"]) - 1

    def add_mesh(self, primitives: list[Primitive]) -> int:
        out = []
        for p in primitives:
            attributes = {"POSITION": self._accessor(p.positions, component=FLOAT, target=ARRAY_BUFFER, bounds=True)}
            if p.normals is not None:
                attributes["NORMAL"] = self._accessor(p.normals, component=FLOAT, target=ARRAY_BUFFER)
            if p.uvs is not None:
                attributes["TEXCOORD_0"] = self._accessor(p.uvs, component=FLOAT, target=ARRAY_BUFFER)
            if p.colors is not None:
                attributes["COLOR_0"] = self._accessor(p.colors, component=FLOAT, target=ARRAY_BUFFER)
            indices = np.arange(len(p.positions), dtype=np.uint32) if p.indices is None else p.indices
            entry: dict[str, Any] = {
                "attributes": attributes,
                "indices": self._accessor(indices, component=UNSIGNED_INT, target=ELEMENT_ARRAY_BUFFER),
                "mode": 4,  # TRIANGLES
            }
            if p.material is not None:
                entry["material"] = p.material
            out.append(entry)
        self._doc["meshes"].append({"primitives": out})
        return len(self._doc["meshes"]) - 1

    def add_node(self, mesh: int, T_root_node: npt.NDArray[np.float64]) -> int:
        """A node drawing ``mesh`` at the 4x4 transform ``T_root_node`` (written column-major, as glTF wants)."""
        node: dict[str, Any] = {"mesh": mesh}
        if not np.allclose(T_root_node, np.eye(4), rtol=0.0, atol=0.0):
            node["matrix"] = [float(v) for v in np.asarray(T_root_node, dtype=np.float64).T.ravel()]
        self._doc["nodes"].append(node)
        return len(self._doc["nodes"]) - 1

    def to_bytes(self) -> bytes:
        doc: dict[str, Any] = {"asset": {"version": "2.0", "generator": "r2d2-viz"}}
        doc.update({k: v for k, v in self._doc.items() if v})
        doc["scene"] = 0
        doc["scenes"] = [{"nodes": list(range(len(self._doc["nodes"])))}]
        self._blob.extend(b"\0" * (-len(self._blob) % 4))
        if self._blob:
            doc["buffers"] = [{"byteLength": len(self._blob)}]
        text = json.dumps(doc, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        chunks = struct.pack("<I4s", len(text), b"JSON") + text
        if self._blob:
            chunks += struct.pack("<I4s", len(self._blob), b"BIN\0") + bytes(self._blob)
        return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def split_glb(glb: bytes) -> tuple[dict[str, Any], bytes]:
    """The JSON document and the BIN chunk of a GLB. Raises ``ValueError`` when it is not one."""
    try:
        magic, version, _ = struct.unpack_from("<4sII", glb)
        size, kind = struct.unpack_from("<I4s", glb, 12)
        if magic != b"glTF" or version != 2 or kind != b"JSON":
            raise ValueError("not a glTF 2.0 binary")
        doc = json.loads(glb[20 : 20 + size])
        rest = glb[20 + size :]
        blob = rest[8 : 8 + struct.unpack_from("<I", rest)[0]] if len(rest) >= 8 and rest[4:8] == b"BIN\0" else b""
    except (struct.error, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"not a readable GLB: {exc}") from None
    except RecursionError:  # JSON nested deeper than Python's parser goes
        raise ValueError("not a readable GLB: its JSON is nested too deeply") from None
    if not isinstance(doc, dict):
        raise ValueError("not a readable GLB: its JSON is not an object")
    return doc, blob


def _primitives(doc: dict[str, Any]) -> list[dict[str, Any]]:
    meshes = doc.get("meshes")
    if not isinstance(meshes, list):
        return []
    found: list[dict[str, Any]] = []
    for mesh in meshes:
        primitives = mesh.get("primitives") if isinstance(mesh, dict) else None
        if isinstance(primitives, list):
            found.extend(p for p in primitives if isinstance(p, dict))
    return found


def _coloured(primitive: dict[str, Any]) -> bool:
    attributes = primitive.get("attributes")
    return "material" in primitive or (isinstance(attributes, dict) and "COLOR_0" in attributes)


def colour_parts(glb: bytes) -> tuple[bool, bool]:
    """(some primitive has a material or vertex colours, some primitive has neither); (False, True) when the bytes
    cannot be read as a GLB (the viewer would then draw them in one default colour, if at all)."""
    try:
        doc, _ = split_glb(glb)
    except ValueError:
        return False, True
    parts = [_coloured(p) for p in _primitives(doc)]
    return any(parts), not all(parts)


def paint_bare_primitives(glb: bytes, rgba: tuple[float, float, float, float]) -> bytes:
    """The GLB with one more material, of colour ``rgba`` (0..1), on each primitive without a colour of its own."""
    doc, blob = split_glb(glb)
    materials = doc.setdefault("materials", [])
    materials.append({"pbrMetallicRoughness": {"baseColorFactor": [float(c) for c in rgba], "metallicFactor": 0.0}})
    for primitive in _primitives(doc):
        if not _coloured(primitive):
            primitive["material"] = len(materials) - 1
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    if blob:
        blob += b"\0" * (-len(blob) % 4)
        chunks += struct.pack("<I4s", len(blob), b"BIN\0") + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks
