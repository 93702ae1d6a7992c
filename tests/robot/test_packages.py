"""Tests for the ROS package resolver (r2d2_viz.robot.packages): $(find pkg) and package:// without ROS."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO

from r2d2_viz.errors import PackageError, UrdfError, UsageError
from r2d2_viz.robot.packages import (
    PackageIndex,
    expected_path,
    missing_files,
    package_xml_name,
    scan_packages,
    uri_package,
)

XACRO = REPO / "tests" / "data" / "xacro"


def make_package(folder: Path, name: str, *files: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "package.xml").write_text(
        f'<?xml version="1.0"?>\n<package format="3">\n  <name>{name}</name>\n  <version>1.0.0</version>\n</package>\n'
    )
    for rel in files:
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_text("solid x\nendsolid x\n")
    return folder


def test_package_xml_name_is_read_from_the_file_not_the_folder() -> None:
    # The clone is named Universal_Robots_ROS2_Description; its package.xml names ur_description.
    assert package_xml_name(XACRO / "Universal_Robots_ROS2_Description") == "ur_description"
    assert package_xml_name(XACRO / "universal_robot" / "ur_description") == "ur_description"
    assert package_xml_name(XACRO) is None


def test_package_xml_with_entities_or_garbage_is_ignored(tmp_path: Path) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "package.xml").write_text(
        '<!DOCTYPE p [<!ENTITY x SYSTEM "file:///etc/passwd">]><package><name>&x;</name></package>'
    )
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "package.xml").write_text("<package><name>unterminated")
    assert package_xml_name(tmp_path / "a") is None
    assert package_xml_name(tmp_path / "b") is None


def test_walk_up_finds_the_enclosing_package_by_its_name() -> None:
    description = XACRO / "Universal_Robots_ROS2_Description" / "urdf" / "ur.urdf.xacro"
    index = PackageIndex(description=description)
    assert index.find("ur_description") == XACRO / "Universal_Robots_ROS2_Description"


def test_siblings_in_the_same_repository_are_found() -> None:
    # kuka_kr6_support's xacro includes $(find kuka_resources): a sibling folder of the same clone.
    description = XACRO / "kuka_experimental" / "kuka_kr6_support" / "urdf" / "kr6r900sixx.xacro"
    index = PackageIndex(description=description)
    assert index.find("kuka_resources") == XACRO / "kuka_experimental" / "kuka_resources"


def test_missing_package_says_where_it_looked(tmp_path: Path) -> None:
    index = PackageIndex.from_args(
        [str(tmp_path)], description=tmp_path / "robot.xacro", environ={"ROS_PACKAGE_PATH": "/nowhere/a:/nowhere/b"}
    )
    with pytest.raises(PackageError) as info:
        index.find("ghost_description")
    message = str(info.value)
    assert isinstance(info.value, UrdfError)
    assert "\n" not in message
    assert message.startswith("package 'ghost_description' not found; looked in the folders above")
    assert f"--package-path {str(tmp_path)!r}" in message
    assert "ROS_PACKAGE_PATH /nowhere/a:/nowhere/b" in message
    assert "AMENT_PREFIX_PATH (unset)" in message


def test_package_path_folder_of_packages_and_pins(tmp_path: Path) -> None:
    ws = tmp_path / "ws" / "src"
    clone = make_package(ws / "Some_Clone" / "arm_description", "arm_description", "meshes/a.stl")
    make_package(ws / "other" / ".hidden" / "secret", "secret")
    make_package(ws / "ignored" / "pkg", "ignored_pkg")
    (ws / "ignored" / "COLCON_IGNORE").write_text("")
    elsewhere = make_package(tmp_path / "elsewhere" / "whatever", "gripper", "m.stl")
    index = PackageIndex.from_args(
        [str(tmp_path / "ws"), f"gripper={elsewhere}"], description=tmp_path / "r.urdf", environ={}
    )
    assert index.find("arm_description") == clone
    assert index.find("gripper") == elsewhere
    assert index.lookup("secret") is None  # hidden folders are not searched
    assert index.lookup("ignored_pkg") is None  # COLCON_IGNORE
    assert scan_packages(tmp_path / "ws") == {"arm_description": clone}


def test_a_pin_wins_over_a_package_found_by_scanning(tmp_path: Path) -> None:
    scanned = make_package(tmp_path / "ws" / "arm", "arm")
    pinned = make_package(tmp_path / "fork" / "arm", "arm")
    index = PackageIndex.from_args([str(tmp_path / "ws"), f"arm={pinned}"], description=None, environ={})
    assert index.find("arm") == pinned != scanned


def test_package_path_that_is_not_a_folder_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="--package-path 'x=/definitely/missing'"):
        PackageIndex.from_args(["x=/definitely/missing"], description=None, environ={})
    with pytest.raises(UsageError, match="is not a folder"):
        PackageIndex.from_args([str(tmp_path / "missing")], description=None, environ={})


def test_ros_package_path_and_ament_index(tmp_path: Path) -> None:
    rpp = make_package(tmp_path / "catkin" / "src" / "legacy_description", "legacy_description")
    prefix = tmp_path / "install"
    share = prefix / "share" / "fancy_description"
    share.mkdir(parents=True)
    marker = prefix / "share" / "ament_index" / "resource_index" / "packages" / "fancy_description"
    marker.parent.mkdir(parents=True)
    marker.write_text("")
    env = {"ROS_PACKAGE_PATH": str(tmp_path / "catkin" / "src"), "AMENT_PREFIX_PATH": f"/nonexistent:{prefix}"}
    index = PackageIndex.from_environ(env)
    assert index.find("legacy_description") == rpp
    assert index.find("fancy_description") == share
    assert index.lookup("not_indexed") is None


def test_an_enclosing_install_prefix_is_used_like_ament_prefix_path(tmp_path: Path) -> None:
    # example-robot-data's layout: <prefix>/share/example-robot-data/robots/x/urdf/x.urdf, indexed by ament.
    prefix = tmp_path / "cmeel.prefix"
    share = prefix / "share" / "example-robot-data"
    urdf_dir = share / "robots" / "x_description" / "urdf"
    urdf_dir.mkdir(parents=True)
    (share / "robots" / "x_description" / "meshes").mkdir()
    (share / "robots" / "x_description" / "meshes" / "m.stl").write_text("solid x\nendsolid x\n")
    marker = prefix / "share" / "ament_index" / "resource_index" / "packages" / "example-robot-data"
    marker.parent.mkdir(parents=True)
    marker.write_text("")
    index = PackageIndex.from_environ({})
    found = index.resolve_uri("package://example-robot-data/robots/x_description/meshes/m.stl", base_dir=urdf_dir)
    assert found == share / "robots" / "x_description" / "meshes" / "m.stl"
    # package:/// with an empty package part, as example-robot-data also writes it (urdfdom keeps it as is)
    found = index.resolve_uri("package:///example-robot-data/robots/x_description/meshes/m.stl", base_dir=urdf_dir)
    assert found == share / "robots" / "x_description" / "meshes" / "m.stl"


def test_resolve_uri_forms(tmp_path: Path) -> None:
    pkg = make_package(tmp_path / "repo" / "clone_name", "real_name", "meshes/a.stl")
    base = pkg / "urdf"
    base.mkdir()
    index = PackageIndex.from_environ({})
    assert index.resolve_uri("package://real_name/meshes/a.stl", base_dir=base) == pkg / "meshes" / "a.stl"
    assert index.resolve_uri("../meshes/a.stl", base_dir=base) == base / ".." / "meshes" / "a.stl"
    assert index.resolve_uri(f"file://{pkg}/meshes/a.stl", base_dir=base) == pkg / "meshes" / "a.stl"
    assert index.resolve_uri(f"package://{pkg}/meshes/a.stl".replace("package://", "package:///"), base_dir=base) == (
        pkg / "meshes" / "a.stl"
    )  # package:///abs/path: an absolute path
    assert index.resolve_uri("package://real_name/meshes/missing.stl", base_dir=base) is None
    assert index.resolve_uri("http://example.com/a.stl", base_dir=base) is None
    path, why = index.explain("package://nope/a.stl", base_dir=base)
    assert path is None and "package 'nope' not found (looked in the folders above" in why
    path, why = index.explain("package://real_name/b.stl", base_dir=base)
    assert path is None and why == f"mesh 'package://real_name/b.stl' not found in package 'real_name' ({str(pkg)!r})"


def test_last_resort_a_folder_named_like_the_package(tmp_path: Path) -> None:
    # What r2d2-viz did before package.xml lookup, kept for loose downloads without a package.xml.
    folder = tmp_path / "r2d2_description"
    (folder / "urdf").mkdir(parents=True)
    assert PackageIndex.from_environ({}).find("r2d2_description", near=folder / "urdf") == folder


def test_scanning_is_bounded(tmp_path: Path) -> None:
    deep = make_package(tmp_path / "a" / "b" / "c" / "d" / "e", "too_deep")
    assert package_xml_name(deep) == "too_deep"
    assert scan_packages(tmp_path) == {}  # deeper than SCAN_DEPTH


def test_uri_package() -> None:
    assert uri_package("package://ur_description/meshes/a.dae") == "ur_description"
    assert uri_package("package:///ur_description/meshes/a.dae") == "ur_description"
    assert uri_package("PACKAGE://a%20b/x.stl") == "a b"
    assert uri_package("file:///a/b.stl") is None
    assert uri_package("meshes/b.stl") is None
    assert uri_package("package://") is None


def test_a_big_workspace_is_counted_not_spelled_out(tmp_path: Path) -> None:
    """A workspace with 300 packages has 300 AMENT_PREFIX_PATH entries: the message names 5 and counts the rest."""
    prefixes = ":".join(f"/ws/install/pkg_{k:03d}" for k in range(300))
    index = PackageIndex.from_args([], description=tmp_path / "robot.xacro", environ={"AMENT_PREFIX_PATH": prefixes})
    with pytest.raises(PackageError) as info:
        index.find("ghost_description")
    message = str(info.value)
    assert "AMENT_PREFIX_PATH (300 entries: /ws/install/pkg_000, " in message and "pkg_004 and 295 more)" in message
    assert len(message) < 600, message


def test_where_a_missing_mesh_would_be_is_named_for_watch(tmp_path: Path) -> None:
    """Issue 44, item 13: ``--watch`` watches a mesh that is missing where it would be found (by hand: the pinned
    package's folder, the URDF's folder for a relative path; no place for an unknown package or an http URI)."""
    (tmp_path / "pkg" / "meshes").mkdir(parents=True)
    (tmp_path / "pkg" / "meshes" / "here.stl").write_text("solid")
    index = PackageIndex(pins={"pkg": tmp_path / "pkg"})
    base = tmp_path / "urdf"
    assert expected_path(index, "package://pkg/meshes/gone.stl", base_dir=base) == tmp_path / "pkg/meshes/gone.stl"
    assert expected_path(index, "meshes/a.stl", base_dir=base) == base / "meshes/a.stl"
    assert expected_path(index, "file:///abs/b.stl", base_dir=base) == Path("/abs/b.stl")
    assert expected_path(index, "package://nowhere/c.stl", base_dir=base) is None
    assert expected_path(index, "http://example.com/d.stl", base_dir=base) is None
    uris = ["package://pkg/meshes/here.stl", "package://pkg/meshes/gone.stl", "package://pkg/meshes/gone.stl"]
    assert missing_files(index, uris, base_dir=base) == (tmp_path / "pkg/meshes/gone.stl",)
