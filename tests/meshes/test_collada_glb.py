"""COLLADA → GLB with pycollada, checked against trimesh on real meshes of example-robot-data.

The independent reference is trimesh: its own COLLADA importer reads each ``.dae`` (``trimesh.load_scene``), and
its glTF importer reads back the GLB we wrote; both scenes are flattened to world-space triangles
(``Scene.to_mesh``) and compared corner by corner. Texture coordinates are compared the same way (trimesh's glTF
reader flips V back into COLLADA's convention, so a wrong flip shows). Colours come from the XML itself.
"""

from __future__ import annotations

import io
import json
import random
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import example_robots
from lxml import etree

from r2d2_viz.meshes.collada_glb import ReadFile, collada_to_glb

ROBOTS = example_robots()
ANYMAL_BASE = ROBOTS / "anymal_b_simple_description/meshes/base/anymal_base.dae"  # textured (a JPEG)
SAMPLES = [
    ROBOTS / "panda_description/meshes/visual/finger.dae",  # two diffuse colours
    ROBOTS / "kinova_description/meshes/hand_2finger.dae",  # a node tree with matrices
    ROBOTS / "anymal_b_simple_description/meshes/hip/anymal_hip_l.dae",
    ANYMAL_BASE,
]


def read_beside(dae: Path) -> ReadFile:
    return lambda name: (dae.parent / name).read_bytes()


def triangles_of(scene: trimesh.Scene) -> np.ndarray:
    """World-space triangles (F, 9), sorted, rounded to 10 µm (float32 positions on one side)."""
    mesh = scene.to_mesh()
    corners = np.round(np.asarray(mesh.triangles, dtype=np.float64).reshape(-1, 9), 5)
    return corners[np.lexsort(corners.T[::-1])]


@pytest.mark.parametrize("dae", SAMPLES, ids=lambda p: p.name)
def test_triangles_match_trimeshs_own_collada_import(dae: Path) -> None:
    glb = collada_to_glb(dae.read_bytes(), read_beside(dae))
    ours = triangles_of(trimesh.load_scene(io.BytesIO(glb), file_type="glb", process=False))
    theirs = triangles_of(trimesh.load_scene(str(dae), process=False))
    assert ours.shape == theirs.shape and len(ours) > 100
    np.testing.assert_allclose(ours, theirs, atol=2e-5)


def test_texture_coordinates_match_trimeshs_and_the_jpeg_is_embedded_as_it_is() -> None:
    glb = collada_to_glb(ANYMAL_BASE.read_bytes(), read_beside(ANYMAL_BASE))
    (n,) = struct.unpack_from("<I", glb, 12)
    doc = json.loads(glb[20 : 20 + n])
    (image,) = doc["images"]
    view = doc["bufferViews"][image["bufferView"]]
    start = 20 + n + 8 + view["byteOffset"]
    assert image["mimeType"] == "image/jpeg"
    assert glb[start : start + view["byteLength"]] == (ANYMAL_BASE.parent / "base_uv_texture.jpg").read_bytes()

    def textured_uvs(scene: trimesh.Scene) -> np.ndarray:
        parts = [
            np.column_stack([np.asarray(g.triangles).reshape(-1, 3), np.asarray(g.visual.uv)[g.faces.ravel()]])
            for g in scene.dump()
            if getattr(g.visual, "uv", None) is not None
        ]
        rows = np.round(np.concatenate(parts), 4)
        return rows[np.lexsort(rows.T[::-1])]

    ours = textured_uvs(trimesh.load_scene(io.BytesIO(glb), file_type="glb", process=False))
    theirs = textured_uvs(trimesh.load_scene(str(ANYMAL_BASE), process=False))
    assert ours.shape == theirs.shape and len(ours) > 1000
    np.testing.assert_allclose(ours, theirs, atol=2e-4)


TRIANGLE = b"""<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><unit meter="0.01"/><up_axis>Z_UP</up_axis></asset>
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array>
<technique_common><accessor source="#pa" count="3" stride="3">
<param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common>
</source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g"/></node></visual_scene>
</library_visual_scenes><scene><instance_visual_scene url="#s"/></scene></COLLADA>"""


def test_unit_scale_and_flat_normals_on_a_hand_written_triangle() -> None:
    # One triangle in centimetres (<unit meter="0.01">), no normals: by hand, the corners become (0,0,0),
    # (0.01,0,0), (0,0.01,0) m and the face normal is +z.
    dae = TRIANGLE
    glb = collada_to_glb(dae, read_beside(Path("/nonexistent/x.dae")))
    mesh = trimesh.load_scene(io.BytesIO(glb), file_type="glb", process=False).to_mesh()
    np.testing.assert_allclose(mesh.triangles[0], [[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0]], atol=1e-7)
    np.testing.assert_allclose(mesh.vertex_normals, [[0, 0, 1]] * 3, atol=1e-6)
    # an index past the end of its source is a clear error (pycollada drops that set), not an IndexError
    with pytest.raises(ValueError, match=r"cannot be read|holds no triangles"):
        collada_to_glb(dae.replace(b"<p>0 1 2</p>", b"<p>0 1 7</p>"), read_beside(Path("/x.dae")))


def _instancing(levels: int) -> bytes:
    """TRIANGLE drawn through <library_nodes>: n0 draws it, each n{k} draws n{k-1} twice, 1 m apart in x."""
    nodes = ['<node id="n0"><instance_geometry url="#g"/></node>']
    for k in range(1, levels + 1):
        nodes.append(
            f'<node id="n{k}"><node><instance_node url="#n{k - 1}"/></node>'
            f'<node><translate>{2 ** (k - 1)} 0 0</translate><instance_node url="#n{k - 1}"/></node></node>'
        )
    library = ("<library_nodes>" + "".join(nodes) + "</library_nodes>").encode()
    return (
        TRIANGLE.replace(b'<unit meter="0.01"/>', b"")
        .replace(b"<library_visual_scenes>", library + b"<library_visual_scenes>")
        .replace(
            b'<instance_geometry url="#g"/></node></visual_scene>',
            f'<instance_node url="#n{levels}"/></node></visual_scene>'.encode(),
        )
    )


def test_an_instanced_geometry_is_one_mesh_drawn_by_several_nodes() -> None:
    dae = _instancing(2)  # four triangles, at x offsets 0, 1, 2, 3 (worked out by hand)
    glb = collada_to_glb(dae, read_beside(Path("/x.dae")))
    (n,) = struct.unpack_from("<I", glb, 12)
    doc = json.loads(glb[20 : 20 + n])
    assert len(doc["meshes"]) == 1 and len(doc["nodes"]) == 4
    flat = trimesh.load_scene(io.BytesIO(glb), file_type="glb", process=False).to_mesh()
    assert sorted(np.round(flat.triangles[:, 0, 0], 6).tolist()) == [0.0, 1.0, 2.0, 3.0]


def test_instances_that_fan_out_are_refused_not_followed() -> None:
    dae = _instancing(40)  # 2**40 triangles if followed
    with pytest.raises(ValueError, match="more than 100000 scene nodes"):
        collada_to_glb(dae, read_beside(Path("/x.dae")))


@pytest.mark.parametrize(
    ("where", "replacement"),
    [
        (b"0 0 0 1 0 0 0 1 0</float_array>", b"0 0 0 1e39 0 0 0 1 0</float_array>"),  # past float32's range
        (b'<node id="n">', b'<node id="n"><matrix>1 0 0 inf 0 1 0 0 0 0 1 0 0 0 0 1</matrix>'),  # a node at infinity
    ],
    ids=["float32-overflow", "infinite-matrix"],  # (pycollada reads a "nan" in a float_array as 0)
)
def test_coordinates_that_are_not_finite_are_refused_quietly(where: bytes, replacement: bytes) -> None:
    assert where in TRIANGLE
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's RuntimeWarnings would reach the user's terminal
        with pytest.raises(ValueError, match=r"not a finite number|not finite"):
            collada_to_glb(TRIANGLE.replace(where, replacement), read_beside(Path("/x.dae")))


def test_a_normal_past_float32s_range_becomes_zero_without_a_warning() -> None:
    normals = (
        b'<source id="nrm"><float_array id="na" count="3">1e39 0 1</float_array><technique_common>'
        b'<accessor source="#na" count="1" stride="3"><param name="X" type="float"/><param name="Y" type="float"/>'
        b'<param name="Z" type="float"/></accessor></technique_common></source>'
    )
    dae = TRIANGLE.replace(b'<vertices id="v">', normals + b'<vertices id="v">').replace(
        b"<p>0 1 2</p>", b'<input semantic="NORMAL" source="#nrm" offset="1"/><p>0 0 1 0 2 0</p>'
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        glb = collada_to_glb(dae, read_beside(Path("/x.dae")))
    mesh = trimesh.load_scene(io.BytesIO(glb), file_type="glb", process=False).to_mesh()
    np.testing.assert_allclose(mesh.triangles[0], [[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0]], atol=1e-7)


def _mangle(data: bytes, rng: random.Random) -> bytes:
    """``data`` with one to four random edits: an element removed, a number or attribute made wrong or cut."""
    root = etree.fromstring(data)
    elements = list(root.iter())
    for _ in range(rng.randint(1, 4)):
        element = rng.choice(elements)
        words = (element.text or "").split()
        op = rng.randrange(4)
        if op == 0 and element.getparent() is not None:
            element.getparent().remove(element)
        elif op == 1 and words:
            words[rng.randrange(len(words))] = rng.choice(["-1", "999999", "inf", "x", "1e308", ""])
            element.text = " ".join(words)
        elif op == 2 and words:
            element.text = " ".join(words[: rng.randrange(len(words))])
        elif op == 3 and element.attrib:
            element.attrib[rng.choice(list(element.attrib))] = rng.choice(["", "#nope", "-1", "99999"])
    return bytes(etree.tostring(root))


def test_mangled_real_files_convert_or_raise_value_error_and_print_nothing() -> None:
    # What the app turns into one warning line per file; anything else would be an unexpected failure (exit 1).
    rng = random.Random(10)
    bases = [(SAMPLES[0], SAMPLES[0].read_bytes()), (Path("/x.dae"), _instancing(2))]  # materials; nodes
    outcomes = {"converted": 0, "refused": 0}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for _ in range(200):
            path, data = rng.choice(bases)
            try:
                collada_to_glb(_mangle(data, rng), read_beside(path))
                outcomes["converted"] += 1
            except ValueError:
                outcomes["refused"] += 1
    assert min(outcomes.values()) > 10, outcomes  # both kinds of outcome are exercised
