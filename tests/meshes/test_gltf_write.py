"""The minimal GLB writer, read back by trimesh's glTF importer (an independent reader) and checked against the
glTF 2.0 binary layout by hand: a 12-byte header whose length is the file's, then 4-byte-aligned chunks."""

from __future__ import annotations

import io
import json
import struct

import numpy as np
import trimesh
from PIL import Image

from r2d2_viz.meshes.gltf_write import GlbBuilder, Material, Primitive, colour_parts, paint_bare_primitives

SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float32)
CORNERS = np.array([0, 1, 2, 0, 2, 3], dtype=np.uint32)


def chunks(glb: bytes) -> list[tuple[bytes, bytes]]:
    magic, version, length = struct.unpack_from("<4sII", glb)
    assert (magic, version, length) == (b"glTF", 2, len(glb))
    out, offset = [], 12
    while offset < len(glb):
        size, kind = struct.unpack_from("<I4s", glb, offset)
        assert size % 4 == 0
        out.append((kind, glb[offset + 8 : offset + 8 + size]))
        offset += 8 + size
    assert offset == len(glb)
    return out


def test_a_coloured_square_lifted_by_its_node_reads_back() -> None:
    builder = GlbBuilder()
    red = builder.add_material(Material(base_color=(1.0, 0.0, 0.0, 1.0)))
    mesh = builder.add_mesh([Primitive(SQUARE, CORNERS, material=red)])
    T_root_node = np.eye(4)
    T_root_node[:3, 3] = (0.0, 0.0, 2.0)
    builder.add_node(mesh, T_root_node)
    glb = builder.to_bytes()
    (json_kind, text), (bin_kind, _) = chunks(glb)
    assert (json_kind, bin_kind) == (b"JSON", b"BIN\0")
    doc = json.loads(text)
    assert doc["nodes"][0]["matrix"][12:15] == [0.0, 0.0, 2.0]  # column-major: translation last
    position = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]]
    assert (position["min"], position["max"]) == ([0.0, 0.0, 0.0], [1.0, 1.0, 0.0])

    loaded = trimesh.load_scene(io.BytesIO(glb), file_type="glb", process=False)
    flat = loaded.to_mesh()
    assert np.isclose(flat.area, 1.0) and np.allclose(flat.vertices[:, 2], 2.0)
    (geometry,) = loaded.geometry.values()
    assert tuple(geometry.visual.material.baseColorFactor) == (255, 0, 0, 255)


def test_an_embedded_texture_and_uvs_read_back() -> None:
    png = io.BytesIO()
    Image.new("RGB", (2, 2), (0, 128, 255)).save(png, format="PNG")
    builder = GlbBuilder()
    texture = builder.add_image(png.getvalue(), "image/png")
    material = builder.add_material(Material(image=texture))
    uvs = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], dtype=np.float32)  # glTF: v down
    normals = np.tile(np.float32([0, 0, 1]), (4, 1))
    builder.add_node(
        builder.add_mesh([Primitive(SQUARE, CORNERS, normals=normals, uvs=uvs, material=material)]), np.eye(4)
    )
    loaded = trimesh.load_scene(io.BytesIO(builder.to_bytes()), file_type="glb", process=False)
    (geometry,) = loaded.geometry.values()
    image = geometry.visual.material.baseColorTexture
    assert image.size == (2, 2) and image.convert("RGB").getpixel((1, 1)) == (0, 128, 255)
    # trimesh turns glTF's v-down into OpenGL's v-up: 1 - v
    np.testing.assert_allclose(geometry.visual.uv, [[0, 0], [1, 0], [1, 1], [0, 1]])
    np.testing.assert_allclose(geometry.vertex_normals, normals)


def test_an_empty_builder_is_still_a_valid_glb() -> None:
    glb = GlbBuilder().to_bytes()
    ((kind, text),) = chunks(glb)
    assert kind == b"JSON" and json.loads(text)["asset"]["version"] == "2.0"


def test_colour_parts_tells_coloured_from_bare_primitives() -> None:
    def glb(*materials: bool, vertex_colours: bool = False) -> bytes:
        builder = GlbBuilder()
        grey = builder.add_material(Material(base_color=(0.5, 0.5, 0.5, 1.0)))
        colours = np.ones((4, 3), dtype=np.float32) if vertex_colours else None
        parts = [Primitive(SQUARE, CORNERS, colors=colours, material=grey if m else None) for m in materials]
        builder.add_node(builder.add_mesh(parts), np.eye(4))
        return builder.to_bytes()

    assert colour_parts(glb(True, True)) == (True, False)
    assert colour_parts(glb(True, False)) == (True, True)
    assert colour_parts(glb(False)) == (False, True)
    assert colour_parts(glb(False, vertex_colours=True)) == (True, False)  # COLOR_0 is a colour of its own
    assert colour_parts(b"solid ascii stl") == (False, True)
    painted = paint_bare_primitives(glb(True, False), (0.0, 0.0, 1.0, 1.0))
    assert colour_parts(painted) == (True, False)
    chunks(painted)  # still a well-formed GLB


def test_hostile_glb_json_reads_as_uncoloured_not_as_a_crash() -> None:
    # A user's .glb goes to the viewer as it is; only its JSON is read here, to tell coloured parts from bare.
    def glb(text: str) -> bytes:
        body = text.encode() + b" " * (-len(text) % 4)
        chunk = struct.pack("<I4s", len(body), b"JSON") + body
        return struct.pack("<4sII", b"glTF", 2, 12 + len(chunk)) + chunk

    assert colour_parts(glb("[" * 100_000)) == (False, True)  # deeper than Python's JSON parser recurses
    assert colour_parts(glb('{"meshes": [{"primitives": 5}]}')) == (False, False)  # no primitive at all
    assert colour_parts(glb('{"meshes": [{"primitives": [{"attributes": 1}, 7]}]}')) == (False, True)
    assert colour_parts(glb('{"meshes": [{"primitives": [{"material": 0}]}, 3, null]}')) == (True, False)
