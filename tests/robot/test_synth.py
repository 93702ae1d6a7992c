"""Synthetic robots for tests and benchmarks: the links and joint types asked for, the same robot per seed."""

from __future__ import annotations

from collections import Counter

import yourdfpy
from lxml import etree

from r2d2_viz.robot.synth import ALL_JOINT_TYPES, random_urdf


def test_links_joint_types_chains_and_seeds(tmp_path) -> None:
    text = random_urdf(60, seed=2)
    root = etree.fromstring(text.encode())
    assert len(root.findall("link")) == 60 and len(root.findall("joint")) == 59
    assert set(Counter(j.get("type") for j in root.findall("joint"))) == set(ALL_JOINT_TYPES)
    assert random_urdf(60, seed=2) == text and random_urdf(60, seed=3) != text
    chain = etree.fromstring(random_urdf(20, seed=1, chain=True, joint_types=("revolute",)).encode())
    assert [j.find("parent").get("link") for j in chain.findall("joint")] == [f"link_{i}" for i in range(19)]
    path = tmp_path / "r.urdf"
    path.write_text(random_urdf(30, seed=5, joint_types=("fixed", "revolute", "prismatic")))
    model = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)  # another parser reads it
    assert len(model.link_map) == 30
