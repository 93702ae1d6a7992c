"""URDF shapes → Rerun archetypes, checked in the saved .rrd (read back with Rerun's reader) on real robots.

Golden values: origins and colours as written in the URDFs (read here by hand), quaternions worked out by hand.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
from meshdata import FINGER, G1_PELVIS, ROBOTS, glb_base_colours, glb_json
from rrd import read_recording

from r2d2_viz.meshes.assets import MeshCache
from r2d2_viz.meshes.gltf_write import GlbBuilder, Material, Primitive
from r2d2_viz.robot.model import Box, MeshFile, Shape, load_urdf
from r2d2_viz.viewer.visuals import COLLISION_COLOR, DEFAULT_VISUAL_COLOR, log_shape, shape_archetypes

PANDA = ROBOTS / "panda_description/urdf/panda.urdf"


def _record(urdf: Path, out: Path, cache: MeshCache) -> list[str]:
    robot = load_urdf(urdf)
    warnings: list[str] = []
    rec = rr.RecordingStream("test_visuals")
    rec.save(out)
    for link in robot.links:
        for i, shape in enumerate(link.visuals):
            log_shape(
                rec, f"/robot/visual/{link.name}/{i}", link.name, shape, visual=True, cache=cache, warn=warnings.append
            )
    rec.flush()
    rec.disconnect()
    return warnings


def _u32(rgba: tuple[int, ...]) -> int:
    r, g, b, a = rgba
    return (r << 24) | (g << 16) | (b << 8) | a


def test_panda_fingers_one_read_own_colours_origin_in_instance_pose(tmp_path: Path) -> None:
    cache = MeshCache(disk=None)
    assert _record(PANDA, tmp_path / "panda.rrd", cache) == []
    recording = read_recording(tmp_path / "panda.rrd")
    left = recording["/robot/visual/panda_leftfinger/0"].static
    right = recording["/robot/visual/panda_rightfinger/0"].static
    assert cache.reads[FINGER.resolve()] == 1  # two links, one read
    assert max(cache.reads.values()) == 1
    blob = bytes(left["Asset3D:blob"][-1][0])
    assert bytes(right["Asset3D:blob"][-1][0]) == blob
    assert left["Asset3D:media_type"][-1] == ["model/gltf-binary"]
    # panda.urdf gives no <material>: the DAE's own two colours reach the viewer, no albedo factor over them
    assert "Asset3D:albedo_factor" not in left or left["Asset3D:albedo_factor"][-1] in (None, [])
    assert len(glb_base_colours(glb_json(blob))) == 2
    assert left["CoordinateFrame:frame"][-1] == ["panda_leftfinger"]
    # panda.urdf: <origin rpy="0 0 3.141592653589793" xyz="0 0 0"/> on the right finger: half a turn about z
    q = np.array(right["InstancePoses3D:quaternions"][-1][0])
    assert np.allclose(np.abs(q), [0, 0, 1, 0], atol=1e-9)
    assert np.allclose(right["InstancePoses3D:translations"][-1][0], [0, 0, 0])
    assert np.allclose(left["InstancePoses3D:quaternions"][-1][0], [0, 0, 0, 1])
    assert np.allclose(right["InstancePoses3D:scales"][-1][0], [1, 1, 1])


def _factor(archetypes: list[rr.AsComponents]) -> int | None:
    (asset,) = [a for a in archetypes if isinstance(a, rr.Asset3D)]
    if asset.albedo_factor is None:
        return None
    (value,) = asset.albedo_factor.as_arrow_array().to_pylist()
    return int(value)


def test_urdf_colour_paints_only_mesh_parts_without_their_own(tmp_path: Path) -> None:
    # RViz's rule (rviz_default_plugins robot_link.cpp, RobotLink::assignMaterialsToEntities; the same in ROS 1's
    # rviz): "Assign materials only if the submesh does not have one already".
    cache = MeshCache(disk=None)
    finger = MeshFile("finger.dae", FINGER)  # every part has its own material: a URDF colour changes nothing
    red = Shape(geometry=finger, rgba=(1.0, 0.0, 0.0, 1.0))
    (asset,) = [a for a in shape_archetypes("l", red, visual=True, cache=cache) if isinstance(a, rr.Asset3D)]
    assert _factor([asset]) is None
    assert asset.blob is not None and bytes(asset.blob.as_arrow_array()[0].values) == cache.asset(FINGER).data
    assert _factor(shape_archetypes("l", Shape(geometry=finger), visual=True, cache=cache)) is None
    # STL has no colours of its own: the URDF colour, or light grey as RViz's default
    stl = MeshFile("pelvis.STL", G1_PELVIS)
    assert _factor(shape_archetypes("l", Shape(geometry=stl, rgba=(1.0, 0.0, 0.0, 1.0)), visual=True, cache=cache)) == (
        0xFF0000FF
    )
    assert _factor(shape_archetypes("l", Shape(geometry=stl), visual=True, cache=cache)) == _u32(DEFAULT_VISUAL_COLOR)
    assert DEFAULT_VISUAL_COLOR == (204, 204, 204, 255)
    # collisions: one translucent orange, whatever the file holds
    assert _factor(shape_archetypes("l", Shape(geometry=finger), visual=False, cache=cache)) == _u32(COLLISION_COLOR)


def test_a_mesh_with_bare_and_coloured_parts_gets_the_urdf_colour_on_the_bare_ones(tmp_path: Path) -> None:
    builder = GlbBuilder()
    green = builder.add_material(Material(base_color=(0.0, 1.0, 0.0, 1.0)))
    triangle = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
    builder.add_node(builder.add_mesh([Primitive(triangle, material=green), Primitive(triangle + 2)]), np.eye(4))
    path = tmp_path / "two.glb"
    path.write_bytes(builder.to_bytes())
    cache = MeshCache(disk=None)
    blue = Shape(geometry=MeshFile("two.glb", path), rgba=(0.0, 0.0, 1.0, 1.0))
    (asset,) = [a for a in shape_archetypes("l", blue, visual=True, cache=cache) if isinstance(a, rr.Asset3D)]
    assert _factor([asset]) is None
    assert asset.blob is not None
    doc = glb_json(bytes(asset.blob.as_arrow_array()[0].values))
    first, second = doc["meshes"][0]["primitives"]
    colours = [m["pbrMetallicRoughness"]["baseColorFactor"] for m in doc["materials"]]
    assert colours[first["material"]] == [0.0, 1.0, 0.0, 1.0]  # its own, kept
    assert colours[second["material"]] == [0.0, 0.0, 1.0, 1.0]  # the URDF's (0 and 1 are the same in sRGB and linear)
    # grey 204 without a URDF colour: sRGB 0.8 is linear ((0.8 + 0.055) / 1.055) ** 2.4 = 0.6038
    (grey,) = [
        a
        for a in shape_archetypes("l", Shape(geometry=blue.geometry), visual=True, cache=cache)
        if isinstance(a, rr.Asset3D)
    ]
    assert grey.blob is not None
    doc = glb_json(bytes(grey.blob.as_arrow_array()[0].values))
    bare = doc["materials"][doc["meshes"][0]["primitives"][1]["material"]]["pbrMetallicRoughness"]["baseColorFactor"]
    assert np.allclose(bare, [0.6038, 0.6038, 0.6038, 1.0], atol=1e-4)


def test_mesh_scale_and_origin_go_to_the_instance_pose() -> None:
    T = np.eye(4)
    T[:3, 3] = [0.1, -0.2, 0.3]
    T[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]  # +90° about z: q = (0, 0, sin 45°, cos 45°)
    shape = Shape(geometry=MeshFile("pelvis.STL", G1_PELVIS, (0.001, 0.002, -0.001)), T_link_shape=T)
    (pose,) = [
        a
        for a in shape_archetypes("l", shape, visual=True, cache=MeshCache(disk=None))
        if isinstance(a, rr.InstancePoses3D)
    ]
    assert pose.translations is not None and pose.quaternions is not None and pose.scales is not None
    assert np.allclose(pose.translations.as_arrow_array().to_pylist(), [[0.1, -0.2, 0.3]])
    assert np.allclose(pose.quaternions.as_arrow_array().to_pylist(), [[0, 0, np.sqrt(0.5), np.sqrt(0.5)]])
    assert np.allclose(pose.scales.as_arrow_array().to_pylist(), [[0.001, 0.002, -0.001]])


def test_undrawable_shapes_warn_once_each_and_log_nothing(tmp_path: Path) -> None:
    warnings: list[str] = []
    cache = MeshCache(disk=None)
    rec = rr.RecordingStream("test_visuals")
    rec.save(tmp_path / "x.rrd")
    missing = Shape(geometry=MeshFile("package://gone/part.stl", None))
    odd = tmp_path / "part.3ds"
    odd.write_bytes(b"\0")
    unsupported = Shape(geometry=MeshFile("part.3ds", odd))
    log_shape(rec, "/a", "base", missing, visual=True, cache=cache, warn=warnings.append)
    log_shape(rec, "/b", "arm", unsupported, visual=True, cache=cache, warn=warnings.append)
    log_shape(rec, "/c", "box", Shape(geometry=Box((1.0, 2.0, 3.0))), visual=True, cache=cache, warn=warnings.append)
    stl = Shape(geometry=MeshFile("pelvis.STL", G1_PELVIS))
    log_shape(rec, "/d", "pelvis", stl, visual=True, cache=cache, warn=warnings.append)
    rec.flush()
    rec.disconnect()
    assert warnings == [
        "link 'base': mesh file 'package://gone/part.stl' not found; shape skipped",
        "link 'arm': mesh file 'part.3ds' has an unsupported format '.3ds' (STL, OBJ, DAE, GLB, GLTF, PLY); "
        "shape skipped",
    ]
    recording = read_recording(tmp_path / "x.rrd")
    assert "/a" not in recording and "/b" not in recording
    # an STL reaches the viewer byte for byte
    assert bytes(recording["/d"].static["Asset3D:blob"][-1][0]) == G1_PELVIS.read_bytes()
    assert recording["/d"].static["Asset3D:media_type"][-1] == ["model/stl"]
    # primitives stay small Mesh3D with their origin baked in (a 1 x 2 x 3 box spans ±0.5, ±1, ±1.5)
    positions = np.array(recording["/c"].static["Mesh3D:vertex_positions"][-1])
    assert np.allclose(positions.min(axis=0), [-0.5, -1, -1.5]) and np.allclose(positions.max(axis=0), [0.5, 1, 1.5])
