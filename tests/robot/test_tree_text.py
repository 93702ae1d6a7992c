"""``r2d2-viz --tree``: the kinematic tree as urdfdom's ``check_urdf`` prints it.

The expected lines are written by hand from check_urdf.cpp (urdfdom, ``printTree``: two indent units of two
spaces per level, ``child(N):  name``) and urdfdom's ``ModelInterface::initTree`` (children in the order of the
``std::map`` of joints, i.e. by joint name) — not produced by the code under test.
"""

from __future__ import annotations

from pathlib import Path

from conftest import cli

from r2d2_viz.robot.model import default_urdf_path, parse_urdf
from r2d2_viz.robot.tree_text import tree_lines

R2D2_TREE = """\
robot name is: r2d2
---------- Successfully Parsed XML ---------------
root Link: axis has 3 child(ren)
    child(1):  leg1  (joint leg1connect, fixed)
    child(2):  leg2  (joint leg2connect, fixed)
    child(3):  body  (joint tilt, revolute)
        child(1):  head  (joint swivel, continuous)
            child(1):  rod  (joint periscope, prismatic)
                child(1):  box  (joint boxconnect, fixed)
"""


def test_the_tutorials_r2d2_prints_as_check_urdf_does() -> None:
    robot = parse_urdf(default_urdf_path().read_bytes(), source="r2d2.urdf")
    assert "\n".join(tree_lines(robot)) + "\n" == R2D2_TREE


def test_children_come_in_the_order_of_their_joints_names_not_the_files() -> None:
    """urdfdom's joints are a std::map: ``a_joint`` (written last) comes first; bytes order (``B`` < ``a``)."""
    text = """<robot name="order">
      <link name="root"/><link name="x"/><link name="y"/><link name="z"/><link name="deep"/>
      <joint name="c_joint" type="fixed"><parent link="root"/><child link="x"/></joint>
      <joint name="a_joint" type="prismatic"><parent link="root"/><child link="y"/>
        <limit lower="0" upper="1" effort="1" velocity="1"/></joint>
      <joint name="B_joint" type="floating"><parent link="root"/><child link="z"/></joint>
      <joint name="d" type="continuous"><parent link="x"/><child link="deep"/></joint>
    </robot>"""
    assert list(tree_lines(parse_urdf(text))) == [
        "robot name is: order",
        "---------- Successfully Parsed XML ---------------",
        "root Link: root has 3 child(ren)",
        "    child(1):  z  (joint B_joint, floating)",
        "    child(2):  y  (joint a_joint, prismatic)",
        "    child(3):  x  (joint c_joint, fixed)",
        "        child(1):  deep  (joint d, continuous)",
    ]


def test_a_single_link_has_no_children_and_a_deep_chain_does_not_recurse() -> None:
    assert list(tree_lines(parse_urdf('<robot name="one"><link name="only"/></robot>')))[2:] == [
        "root Link: only has 0 child(ren)"
    ]
    links = "".join(f'<link name="l{i}"/>' for i in range(3001))
    joints = "".join(
        f'<joint name="j{i}" type="fixed"><parent link="l{i}"/><child link="l{i + 1}"/></joint>' for i in range(3000)
    )
    lines = list(tree_lines(parse_urdf(f'<robot name="chain">{links}{joints}</robot>')))
    assert len(lines) == 3 + 3000
    assert lines[-1] == " " * 4 * 3000 + "child(1):  l3000  (joint j2999, fixed)"


def test_cli_tree_prints_and_exits_0() -> None:
    result = cli("--tree")
    assert result.returncode == 0, result.stderr
    assert result.stdout == R2D2_TREE


def test_cli_tree_of_a_broken_description_is_one_line_and_exit_2(tmp_path: Path) -> None:
    broken = tmp_path / "broken.urdf"
    broken.write_text(
        '<robot name="b"><link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="nope"/>'
        "</joint></robot>"
    )
    result = cli("--urdf", str(broken), "--tree")
    assert result.returncode == 2
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: broken.urdf:") and "nope" in lines[0], result.stderr


def test_cli_tree_says_impossible_inertias_on_stderr_one_line_each(tmp_path: Path) -> None:
    urdf = tmp_path / "heavy.urdf"
    urdf.write_text(
        '<robot name="h"><link name="a"><inertial><mass value="1"/>'
        '<inertia ixx="0.001" iyy="0.001" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>'
    )
    result = cli("--urdf", str(urdf), "--tree")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[2] == "root Link: a has 0 child(ren)"
    assert result.stderr.splitlines() == [
        "warning: heavy.urdf: link 'a': <inertial>: principal moments 0.001, 0.001, 0.01 kg·m² violate the triangle "
        "inequality (0.001 + 0.001 < 0.01)"
    ]
