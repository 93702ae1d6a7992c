"""Real meshes of example-robot-data (PyPI, a test dependency) and a GLB's JSON read by hand (struct + json),
shared by the mesh, cache and visuals tests."""

from __future__ import annotations

import json
import struct

from conftest import example_robots

ROBOTS = example_robots()
FINGER = ROBOTS / "panda_description/meshes/visual/finger.dae"  # two plain diffuse colours
G1_PELVIS = ROBOTS / "g1_description/meshes/pelvis.STL"


def glb_json(glb: bytes) -> dict:
    """The JSON chunk of a GLB (glTF 2.0 binary: 12-byte header, then length, type 'JSON', data)."""
    magic, version, length = struct.unpack("<4sII", glb[:12])
    assert (magic, version, length) == (b"glTF", 2, len(glb))
    chunk_length, chunk_type = struct.unpack("<I4s", glb[12:20])
    assert chunk_type == b"JSON"
    return json.loads(glb[20 : 20 + chunk_length])


def glb_base_colours(doc: dict) -> list[list[float]]:
    return [m["pbrMetallicRoughness"]["baseColorFactor"] for m in doc.get("materials", [])]
