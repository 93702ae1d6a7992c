"""Mesh files → viewer bytes, on real meshes of example-robot-data (PyPI, a test dependency).

Golden values come from the files themselves, read here by hand: colours and triangle counts from the COLLADA
XML (ElementTree), the converted GLB's materials and primitives from its JSON chunk (struct + json).
"""

from __future__ import annotations

import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from meshdata import FINGER, G1_PELVIS, ROBOTS, glb_base_colours, glb_json

from r2d2_viz.meshes import assets as meshes
from r2d2_viz.meshes.assets import MeshCache
from r2d2_viz.meshes.disk_cache import DiskCache

FOOT = ROBOTS / "anymal_b_simple_description/meshes/foot/anymal_foot.dae"  # a broken material reference
NS = {"c": "http://www.collada.org/2005/11/COLLADASchema"}


def dae_diffuse_colours(path: Path) -> list[tuple[float, ...]]:
    root = ET.parse(path).getroot()
    return [
        tuple(float(v) for v in (color.text or "").split())
        for color in root.iterfind(".//c:effect//c:diffuse/c:color", NS)
    ]


def dae_triangle_count(path: Path) -> int:
    root = ET.parse(path).getroot()
    return sum(int(t.get("count", "0")) for t in root.iterfind(".//c:geometry//c:triangles", NS))


def glb_triangle_count(doc: dict) -> int:
    return sum(doc["accessors"][p["indices"]]["count"] // 3 for m in doc["meshes"] for p in m["primitives"])


def test_dae_keeps_its_own_colours_and_triangles() -> None:
    asset = MeshCache(disk=None).asset(FINGER)
    assert asset.media_type == "model/gltf-binary" and asset.own_colors
    doc = glb_json(asset.data)
    expected = dae_diffuse_colours(FINGER)
    assert len(expected) == 2  # dark grey and white, from the XML
    got = glb_base_colours(doc)
    assert sorted(np.round(got, 2).tolist()) == sorted(np.round(expected, 2).tolist())
    assert glb_triangle_count(doc) == dae_triangle_count(FINGER) == 262 + 362


def test_broken_material_reference_still_shows_geometry() -> None:
    # anymal_foot.dae: the carbon material's sampler names a surface that does not exist; pycollada then
    # drops the whole node (r2d2-viz used to say "holds no triangles"). RViz shows the foot.
    asset = MeshCache(disk=None).asset(FOOT)
    doc = glb_json(asset.data)
    assert glb_triangle_count(doc) == dae_triangle_count(FOOT) == 81 + 4484 + 39
    colours = np.round(glb_base_colours(doc), 2).tolist()
    solid = [c for c in dae_diffuse_colours(FOOT)]  # the two intact materials keep their colour
    assert sorted(colours) == sorted(np.round(solid, 2).tolist())


def test_stl_goes_to_the_viewer_as_it_is() -> None:
    asset = MeshCache(disk=None).asset(G1_PELVIS)
    assert asset.data == G1_PELVIS.read_bytes()
    assert asset.media_type == "model/stl" and not asset.own_colors


def test_each_file_is_read_once_however_often_it_is_asked_for() -> None:
    cache = MeshCache(disk=None)
    first = cache.asset(FINGER)
    for _ in range(3):
        assert cache.asset(FINGER) is first
    assert cache.asset(G1_PELVIS) is cache.asset(G1_PELVIS)
    assert cache.reads == {FINGER.resolve(): 1, G1_PELVIS.resolve(): 1}


def test_unreadable_files_name_the_file_and_are_tried_once(tmp_path: Path) -> None:
    cache = MeshCache(disk=None)
    odd = tmp_path / "part.3ds"
    odd.write_bytes(b"\0" * 16)
    with pytest.raises(ValueError, match=r"mesh file 'package://x/part.3ds' has an unsupported format '.3ds'"):
        cache.asset(odd, "package://x/part.3ds")
    garbage = tmp_path / "garbage.dae"
    garbage.write_bytes(b"<COLLADA><not closed")
    for _ in range(2):
        with pytest.raises(ValueError, match=r"garbage.dae' cannot be read"):
            cache.asset(garbage)
    assert cache.reads[garbage.resolve()] == 1


def _no_conversion(*args: object) -> tuple[bytes, dict[str, str]]:
    raise AssertionError("converted although the disk cache holds the file")


def test_disk_cache_is_keyed_by_content_and_survives_deletion_and_corruption(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    disk = DiskCache(tmp_path / "cache")
    glb = MeshCache(disk).asset(FINGER).data
    (entry,) = (tmp_path / "cache").iterdir()

    # Same content under another name and folder: served from the cache, no conversion.
    copy = tmp_path / "elsewhere" / "renamed.dae"
    copy.parent.mkdir()
    shutil.copyfile(FINGER, copy)
    with monkeypatch.context() as m:
        m.setattr(meshes, "convert_to_glb", _no_conversion)
        assert MeshCache(disk).asset(copy).data == glb

    # Changed content: a new entry.
    copy.write_bytes(FINGER.read_bytes().replace(b"0.2509804 0.2509804 0.2509804", b"1 0 0"))
    changed = glb_json(MeshCache(disk).asset(copy).data)
    assert [1.0, 0.0, 0.0, 1.0] in glb_base_colours(changed)
    assert len(list((tmp_path / "cache").iterdir())) == 2

    # A corrupt entry (one byte flipped, or truncated) is ignored and rewritten.
    for damage in (lambda b: b[:-100] + bytes([b[-100] ^ 0xFF]) + b[-99:], lambda b: b[: len(b) // 2]):
        entry.write_bytes(damage(entry.read_bytes()))
        assert MeshCache(disk).asset(FINGER).data == glb
        with monkeypatch.context() as m:
            m.setattr(meshes, "convert_to_glb", _no_conversion)
            assert MeshCache(disk).asset(FINGER).data == glb

    # Deleting the whole folder is safe.
    shutil.rmtree(tmp_path / "cache")
    assert MeshCache(disk).asset(FINGER).data == glb
    assert entry.exists()
    assert not [p for p in (tmp_path / "cache").iterdir() if p.name.startswith(".tmp-")]


LAIKAGO = ROBOTS / "laikago_description/meshes"
GLTF_ATTRIBUTE = r"(POSITION|NORMAL|TANGENT|TEXCOORD_\d+|COLOR_\d+|JOINTS_\d+|WEIGHTS_\d+)"


def test_obj_with_material_library_keeps_its_colours_in_a_glb_rerun_can_read() -> None:
    cache = MeshCache(disk=None)
    trunk = cache.asset(LAIKAGO / "trunk.obj")  # "mtllib trunk.mtl": Kd 1.0 0.4235 0.0392 (orange)
    kd = [
        [float(v) for v in line.split()[1:4]]
        for line in (LAIKAGO / "trunk.mtl").read_text().splitlines()
        if line.startswith("Kd ")
    ]
    assert trunk.media_type == "model/gltf-binary"
    got = [c[:3] for c in glb_base_colours(glb_json(trunk.data))]
    assert got and all(np.allclose(c, kd[0], atol=1 / 255) for c in got)
    assert cache.reads[(LAIKAGO / "trunk.obj").resolve()] == 1
    # hip.obj has per-vertex colours ("v x y z r g b"); trimesh would write them as a custom "_color"
    # attribute, which Rerun's glTF reader refuses ("invalid semantic name"), dropping the whole mesh.
    hip = glb_json(cache.asset(LAIKAGO / "hip.obj").data)
    names = {name for mesh in hip["meshes"] for p in mesh["primitives"] for name in p["attributes"]}
    assert "POSITION" in names and all(re.fullmatch(GLTF_ATTRIBUTE, name) for name in names), names


ANYMAL_BASE = ROBOTS / "anymal_b_simple_description/meshes/base"  # anymal_base.dae + base_uv_texture.jpg


def test_textures_are_embedded_and_a_changed_texture_invalidates_the_cache_entry(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    base = tmp_path / "base"
    shutil.copytree(ANYMAL_BASE, base)
    dae = base / "anymal_base.dae"
    root = ET.parse(dae).getroot()
    images = [e.text for e in root.iterfind(".//c:library_images/c:image/c:init_from", NS)]
    assert images == ["base_uv_texture.jpg"]
    disk = DiskCache(tmp_path / "cache")
    doc = glb_json(MeshCache(disk).asset(dae).data)
    assert len(doc.get("images", [])) == 1
    textured = [m for m in doc["materials"] if "baseColorTexture" in m.get("pbrMetallicRoughness", {})]
    assert textured

    calls: list[Path] = []

    def counting(path: Path, data: bytes, suffix: str | None = None) -> tuple[bytes, dict[str, str]]:
        calls.append(path)
        return b"glTF", {}

    monkeypatch.setattr(meshes, "convert_to_glb", counting)
    MeshCache(disk).asset(dae)
    assert calls == []  # texture unchanged: the entry is used
    (base / "base_uv_texture.jpg").write_bytes(b"another texture")
    MeshCache(disk).asset(dae)
    assert calls == [dae.resolve()]


def test_a_dae_without_materials_counts_as_colourless() -> None:
    # kinova's jaco_mounting_block.dae has no <library_materials> / <library_effects> (checked by hand here),
    # so a URDF without <material> shows it in the default grey rather than the viewer's own default.
    block = ROBOTS / "kinova_description/meshes/jaco_mounting_block.dae"
    root = ET.parse(block).getroot()
    assert root.find(".//c:material", NS) is None and root.find(".//c:effect", NS) is None
    assert not MeshCache(disk=None).asset(block).own_colors
    assert MeshCache(disk=None).asset(FINGER).own_colors


def test_hostile_collada_with_entities_is_refused_quickly(tmp_path: Path) -> None:
    finger = FINGER.read_text()
    header, _, rest = finger.partition("<COLLADA")
    # 10**6 "lol"s: harmless if it were ever expanded, so without the refusal the test fails instead of hanging
    laughs = "".join(f'<!ENTITY l{i} "{f"&l{i - 1};" * 10 if i else "lol"}">' for i in range(7))
    variants = {
        "laughs": (f"<!DOCTYPE c [{laughs}]>", "&l6;"),
        "file": ('<!DOCTYPE c [<!ENTITY x SYSTEM "file:///etc/hostname">]>', "&x;"),
    }
    for name, (dtd, reference) in variants.items():
        hostile = tmp_path / f"{name}.dae"
        hostile.write_text(header + dtd + "<COLLADA" + rest.replace("<author>", f"<author>{reference}", 1))
        with pytest.raises(ValueError, match=r"declares a DTD or entities"):
            MeshCache(disk=None).asset(hostile)


def test_device_files_are_never_read(tmp_path: Path) -> None:
    zero_stl = tmp_path / "zero.stl"
    zero_stl.symlink_to("/dev/zero")
    with pytest.raises(ValueError, match=r"is not a regular file"):
        MeshCache(disk=None).asset(zero_stl)
    # an OBJ whose material library names /dev/zero as its texture: converted without it, not read forever
    shutil.copyfile(LAIKAGO / "trunk.obj", tmp_path / "trunk.obj")
    mtl = (LAIKAGO / "trunk.mtl").read_text().replace("Kd 1.0", "map_Kd /dev/zero\nKd 1.0", 1)
    (tmp_path / "trunk.mtl").write_text(mtl)
    assert MeshCache(disk=None).asset(tmp_path / "trunk.obj").media_type == "model/gltf-binary"


def test_a_marker_mesh_resource_uri_loads_through_the_package_resolver(tmp_path: Path) -> None:
    from r2d2_viz.meshes.assets import uri_loader
    from r2d2_viz.robot.packages import PackageIndex

    # --package-path NAME=DIR, as a user names a package without a package.xml: package://panda_description/…
    packages = PackageIndex.from_args(
        [f"panda_description={ROBOTS / 'panda_description'}"], description=None, environ={}
    )
    load = uri_loader(packages, tmp_path)
    found = load("package://panda_description/meshes/visual/finger.dae")
    assert found is not None
    data, media_type = found
    assert media_type == "model/gltf-binary" and data[:4] == b"glTF"  # COLLADA reaches the viewer as GLB
    assert load("package://no_such_package/x.stl") is None
    assert load("package://panda_description/meshes/visual/missing.dae") is None
