"""Tests for safe XML reading (r2d2_viz.robot.urdf_xml); the bad corpus in tests/test_urdf_check.py covers the rest."""

from __future__ import annotations

import pytest
from conftest import REPO

from r2d2_viz.errors import UrdfError
from r2d2_viz.robot.urdf_xml import MAX_FILE_BYTES, parse_urdf_xml, read_urdf_xml

GOOD = REPO / "tests" / "data" / "good"
BAD = REPO / "tests" / "data" / "bad"


def test_file_and_text_give_the_same_robot() -> None:
    path = GOOD / "r2d2_tutorial.urdf"
    from_file = read_urdf_xml(path)
    from_text = parse_urdf_xml(path.read_text(), source="r2d2", base_dir=GOOD)
    assert [el.get("name") for el in from_file] == [el.get("name") for el in from_text]
    assert from_file.getroottree().docinfo.URL == str(path.absolute())


@pytest.mark.parametrize("name", ["billion_laughs.urdf", "xxe_file.urdf", "xxe_parameter_entity.urdf"])
def test_entities_are_refused_from_text_too(name: str) -> None:
    with pytest.raises(UrdfError, match=r"^robot_description: DOCTYPE declares entities"):
        parse_urdf_xml((BAD / name).read_bytes(), source="robot_description", base_dir=BAD)


def test_oversized_text_is_refused_before_parsing() -> None:
    with pytest.raises(UrdfError, match=r"^big: description is too large"):
        parse_urdf_xml(b" " * (MAX_FILE_BYTES + 1), source="big", base_dir=GOOD)
