"""Tests for xacro expansion (r2d2_viz.robot.xacro_load): real descriptions from public repositories expand like
plain xacro does, hostile files run nothing, errors are one line naming the file and the chain."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, cli
from xacro_cases import canonical, plain_xacro, refusal, write

from r2d2_viz.errors import UsageError
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.xacro_load import expand_xacro, is_xacro, load_description, load_robot

XACRO = REPO / "tests" / "data" / "xacro"
GOOD = REPO / "tests" / "data" / "good"

# (file, xacro arguments, links, joints): the real descriptions under tests/data/xacro (see its README).
# Link and joint counts come from the upstream files (counted by hand in the expanded output of plain xacro,
# which test_same_urdf_as_plain_xacro compares against).
REAL = [
    ("urdf_tutorial/urdf/08-macroed.urdf.xacro", {}, 16, 15),
    ("Universal_Robots_ROS2_Description/urdf/ur.urdf.xacro", {"ur_type": "ur5e", "name": "ur"}, 13, 12),
    ("universal_robot/ur_description/urdf/ur5e.xacro", {}, 11, 10),
    ("franka_ros/franka_description/robots/panda/panda.urdf.xacro", {}, 17, 16),
    ("pr2_common/pr2_description/robots/pr2.urdf.xacro", {}, 88, 87),
    ("kuka_experimental/kuka_kr6_support/urdf/kr6r900sixx.xacro", {}, 10, 9),
]
# Where each package of those files is, for plain xacro (its $(find) asks ament_index_python).
PACKAGES = {
    "urdf_tutorial": "urdf_tutorial",
    "ur_description": "Universal_Robots_ROS2_Description",
    "franka_description": "franka_ros/franka_description",
    "pr2_description": "pr2_common/pr2_description",
    "kuka_kr6_support": "kuka_experimental/kuka_kr6_support",
    "kuka_resources": "kuka_experimental/kuka_resources",
}
# --------------------------------------------------------------------------- real descriptions


@pytest.mark.parametrize(("rel", "args", "n_links", "n_joints"), REAL, ids=[r[0].split("/")[0] for r in REAL])
def test_real_description_expands_like_plain_xacro(
    tmp_path: Path, rel: str, args: dict[str, str], n_links: int, n_joints: int
) -> None:
    path = XACRO / rel
    packages = {k: XACRO / v for k, v in PACKAGES.items()}
    if rel.startswith("universal_robot/"):  # the ROS 1 package of the same name
        packages["ur_description"] = XACRO / "universal_robot" / "ur_description"
    reference = plain_xacro(tmp_path, path, args, packages)
    ours = expand_xacro(path, mappings=args, packages=PackageIndex(description=path))
    out, err = reference.communicate(timeout=120)
    assert reference.returncode == 0, err
    assert canonical(ours) == canonical(out)
    robot = load_robot(path, mappings=args)
    assert (len(robot.links), len(robot.joints)) == (n_links, n_joints)


def pal_urdf_utils_stand_in(folder: Path) -> Path:
    """pal_urdf_utils is licensed CC BY-NC-ND, so it is not copied here: a stand-in with the one property the
    TIAGo files use from it (deg_to_rad, i.e. pi/180) and no materials (their colours then fall back, with
    a warning each)."""
    root = folder / "pal_urdf_utils"
    (root / "urdf").mkdir(parents=True)
    (root / "package.xml").write_text('<package format="3"><name>pal_urdf_utils</name></package>')
    ns = 'xmlns:xacro="http://ros.org/wiki/xacro"'
    (root / "urdf" / "deg_to_rad.urdf.xacro").write_text(
        f'<robot {ns}><xacro:property name="deg_to_rad" value="{math.pi / 180!r}"/></robot>'
    )
    (root / "urdf" / "materials.urdf.xacro").write_text(f"<robot {ns}/>")
    return folder


def test_tiago_expands_like_plain_xacro_with_its_dependencies_on_package_path(tmp_path: Path) -> None:
    path = XACRO / "tiago_robot" / "tiago_description" / "robots" / "tiago.urdf.xacro"
    stand_in = pal_urdf_utils_stand_in(tmp_path / "deps")
    packages = {
        "tiago_description": XACRO / "tiago_robot" / "tiago_description",
        "tiago_controller_configuration": XACRO / "tiago_robot" / "tiago_controller_configuration",
        "pmb2_description": XACRO / "pmb2_robot" / "pmb2_description",
        "pal_hey5_description": XACRO / "pal_hey5" / "pal_hey5_description",
        "pal_urdf_utils": stand_in / "pal_urdf_utils",
    }
    reference = plain_xacro(tmp_path, path, {}, packages)
    index = PackageIndex.from_args([str(stand_in)], description=path, environ={})
    ours = expand_xacro(path, mappings={}, packages=index)
    out, err = reference.communicate(timeout=120)
    assert reference.returncode == 0, err
    assert canonical(ours) == canonical(out)
    robot = load_robot(path, packages=index)
    assert (len(robot.links), len(robot.joints)) == (89, 88)
    # the CLI: without the dependency on --package-path, one line saying where it looked
    result = cli("--urdf", str(path), "--headless", "--duration", "0.1", env={"ROS_PACKAGE_PATH": ""})
    assert result.returncode == 2
    assert result.stderr.startswith("error: base.urdf.xacro: package 'pal_urdf_utils' not found; looked in")
    assert result.stderr.rstrip().endswith("(included from base_sensors.urdf.xacro < tiago.urdf.xacro)")
    result = cli("--urdf", str(path), "--package-path", str(stand_in), "--headless", "--duration", "0.1")
    assert result.returncode == 0, result.stderr


def test_ur5e_joint_origins_come_from_its_yaml() -> None:
    # config/ur5e/default_kinematics.yaml (Universal Robots' calibration): shoulder z 0.1625, forearm x -0.425,
    # wrist_1 x -0.3922 z 0.1333, read by the xacro through xacro.load_yaml.
    path = XACRO / "Universal_Robots_ROS2_Description" / "urdf" / "ur.urdf.xacro"
    robot = load_robot(path, mappings={"ur_type": "ur5e", "name": "ur"})
    origin = {j.name: j.T_parent_joint[:3, 3] for j in robot.joints}
    np.testing.assert_allclose(origin["shoulder_pan_joint"], [0, 0, 0.1625])
    np.testing.assert_allclose(origin["elbow_joint"], [-0.425, 0, 0])
    np.testing.assert_allclose(origin["wrist_1_joint"], [-0.3922, 0, 0.1333])
    limits = {j.name: j.limit for j in robot.joints if j.limit is not None}
    # config/ur5e/joint_limits.yaml: shoulder_pan ±2π (max_position / min_position: !degrees 360)
    assert limits["shoulder_pan_joint"].upper == pytest.approx(2 * math.pi)


def test_meshes_of_an_expanded_xacro_resolve_through_the_package() -> None:
    robot = load_robot(XACRO / "urdf_tutorial" / "urdf" / "08-macroed.urdf.xacro")
    meshes = {s.geometry.path for link in robot.links for s in link.visuals if hasattr(s.geometry, "path")}
    assert XACRO / "urdf_tutorial" / "meshes" / "l_finger.dae" in meshes
    assert robot.warnings == ()


def test_cli_records_a_xacro_with_arguments(tmp_path: Path) -> None:
    out = tmp_path / "ur.rrd"
    path = XACRO / "Universal_Robots_ROS2_Description" / "urdf" / "ur.urdf.xacro"
    result = cli("--urdf", str(path), "ur_type:=ur5e", "name:=ur", "--save", str(out), "--duration", "1")
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 0
    # the meshes were left out of tests/data: one warning each, naming the package folder
    assert "mesh 'package://ur_description/meshes/ur5e/visual/base.dae' not found in package 'ur_description'" in (
        result.stderr
    )


def test_cli_package_path_finds_a_dependency_in_another_folder(tmp_path: Path) -> None:
    # A robot xacro in one folder using a package from another clone: found only with --package-path.
    robot_dir = tmp_path / "my_robot" / "urdf"
    robot_dir.mkdir(parents=True)
    (robot_dir / "robot.urdf.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r">\n'
        '  <xacro:include filename="$(find kuka_resources)/urdf/common_materials.xacro"/>\n'
        '  <xacro:include filename="$(find kuka_resources)/urdf/common_constants.xacro"/>\n'
        '  <link name="base"><visual><geometry><box size="${DEG2RAD} 1 1"/></geometry></visual></link>\n</robot>\n'
    )
    out = tmp_path / "r.rrd"
    args = ["--urdf", str(robot_dir / "robot.urdf.xacro"), "--save", str(out), "--duration", "0.1"]
    result = cli(*args, env={"ROS_PACKAGE_PATH": "", "AMENT_PREFIX_PATH": ""})
    assert result.returncode == 2
    assert result.stderr.startswith("error: robot.urdf.xacro: package 'kuka_resources' not found; looked in")
    assert len(result.stderr.splitlines()) == 1
    result = cli(*args, "--package-path", str(XACRO / "kuka_experimental"))
    assert result.returncode == 0, result.stderr


def test_bad_xacro_argument_is_a_usage_error(tmp_path: Path) -> None:
    result = cli("--urdf", str(XACRO / "urdf_tutorial" / "urdf" / "08-macroed.urdf.xacro"), "nonsense", "--headless")
    assert result.returncode == 2
    assert result.stderr == "error: 'nonsense': expected a xacro argument NAME:=VALUE\n"


def test_xacro_arguments_for_a_plain_urdf_are_refused() -> None:
    with pytest.raises(UsageError, match=r"arguments for a xacro file, but r2d2_tutorial\.urdf is not one"):
        load_robot(GOOD / "r2d2_tutorial.urdf", mappings={"a": "1"})


def test_detection_by_extension_or_namespace(tmp_path: Path) -> None:
    assert is_xacro(Path("a.urdf.xacro"), b"")
    assert is_xacro(Path("a.urdf"), b'<robot xmlns:xacro="http://wiki.ros.org/xacro"><xacro:property/></robot>')
    assert is_xacro(Path("a.urdf"), b"<robot xmlns:x = 'http://www.ros.org/wiki/xacro'><link name='${n}'/></robot>")
    # xacro's own output keeps the declaration (38 of example-robot-data's URDFs): loaded as it is
    assert not is_xacro(Path("a.urdf"), b'<robot xmlns:xacro="http://wiki.ros.org/xacro"><!-- ${x} --></robot>')
    assert not is_xacro(Path("a.urdf"), (GOOD / "r2d2_tutorial.urdf").read_bytes())
    # a plain URDF passes through untouched, as bytes
    description = load_description(GOOD / "r2d2_tutorial.urdf")
    assert description.text == (GOOD / "r2d2_tutorial.urdf").read_bytes()


# --------------------------------------------------------------------------- errors


def test_error_names_the_file_the_macro_and_the_include_chain(tmp_path: Path) -> None:
    (tmp_path / "parts.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
        '  <xacro:macro name="wheel" params="side"><link name="${side}_${undefined_size}"/></xacro:macro>\n'
        "</robot>\n"
    )
    path = write(tmp_path, '<xacro:include filename="parts.xacro"/>\n<xacro:wheel side="left"/>')
    message = refusal(path)
    assert message.startswith("robot.urdf.xacro: name 'undefined_size' is not defined when evaluating expression")
    assert "(in macro 'wheel')" in message


def test_error_inside_an_included_file_names_the_chain(tmp_path: Path) -> None:
    inner = '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="${1/0}"/></robot>'
    (tmp_path / "inner.xacro").write_text(inner)
    path = write(tmp_path, '<xacro:include filename="inner.xacro"/>')
    message = refusal(path)
    assert message.startswith("inner.xacro: division by zero")
    assert message.endswith("(included from robot.urdf.xacro)")


def test_missing_argument_says_how_to_pass_it() -> None:
    message = refusal(XACRO / "Universal_Robots_ROS2_Description" / "urdf" / "ur.urdf.xacro")
    assert message == "ur.urdf.xacro: xacro argument 'name' is not set (pass name:=VALUE)"


def test_missing_package_says_where_it_looked(tmp_path: Path) -> None:
    path = write(tmp_path, '<xacro:include filename="$(find ghost_description)/urdf/g.xacro"/>')
    message = refusal(path, packages=PackageIndex.from_environ({}, description=path))
    assert message.startswith(
        f"robot.urdf.xacro: package 'ghost_description' not found; looked in the folders above '{tmp_path}'"
    )
    assert "ROS_PACKAGE_PATH (unset); AMENT_PREFIX_PATH (unset)" in message


def test_missing_include_and_bad_xml(tmp_path: Path) -> None:
    assert refusal(write(tmp_path, '<xacro:include filename="nope.xacro"/>')).startswith(
        f"robot.urdf.xacro: No such file or directory: {tmp_path / 'nope.xacro'}"
    )
    (tmp_path / "broken.xacro").write_text("<robot><link></robot>")
    assert refusal(tmp_path / "broken.xacro").startswith("broken.xacro: not well-formed XML: mismatched tag: line 1")


def test_data_readme_lists_every_repository() -> None:
    readme = (XACRO / "README.md").read_text()
    for folder in XACRO.iterdir():
        if folder.is_dir():
            assert f"`{folder.name}/`" in readme, folder.name
            assert any(folder.glob("LICENSE*")) or f"`{folder.name}/` has no licence file" in readme
