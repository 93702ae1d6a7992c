"""Tests for xacro expansion (r2d2_viz.xacro_load): real descriptions from public repositories expand like
plain xacro does, hostile files run nothing, errors are one line naming the file and the chain."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from lxml import etree

from r2d2_viz import xacro_load
from r2d2_viz.errors import UrdfError, UsageError, XacroError
from r2d2_viz.packages import PackageIndex
from r2d2_viz.xacro_load import expand_xacro, is_xacro, load_description, load_robot

XACRO = Path(__file__).parent / "data" / "xacro"
GOOD = Path(__file__).parent / "data" / "good"

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
FAKE_AMENT = """import json, os
def get_package_share_directory(name):
    return json.loads(os.environ["R2D2_TEST_PACKAGES"])[name]
"""


def canonical(xml: str | bytes) -> bytes:
    parser = etree.XMLParser(remove_blank_text=True, remove_comments=True, resolve_entities=False)
    data = xml.encode() if isinstance(xml, str) else xml
    return etree.tostring(etree.fromstring(data, parser), method="c14n")


def plain_xacro(tmp_path: Path, path: Path, args: dict[str, str], packages: dict[str, Path]) -> subprocess.Popen[str]:
    """Run the unmodified ``xacro`` command (the reference), with a stand-in ament index for $(find)."""
    exe = Path(sys.executable).parent / "xacro"
    if not exe.exists():
        pytest.skip("the xacro command is not installed beside python")
    (tmp_path / "ament_index_python").mkdir(exist_ok=True)
    (tmp_path / "ament_index_python" / "__init__.py").write_text("")
    (tmp_path / "ament_index_python" / "packages.py").write_text(FAKE_AMENT)
    env = {
        **os.environ,
        "PYTHONPATH": str(tmp_path),
        "R2D2_TEST_PACKAGES": json.dumps({k: str(v) for k, v in packages.items()}),
    }
    command = [str(exe), str(path), *(f"{k}:={v}" for k, v in args.items())]
    return subprocess.Popen(command, env=env, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


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
    assert is_xacro(Path("a.urdf"), b'<robot xmlns:xacro="http://wiki.ros.org/xacro">')
    assert is_xacro(Path("a.urdf"), b"<robot xmlns:x = 'http://www.ros.org/wiki/xacro'>")
    assert not is_xacro(Path("a.urdf"), (GOOD / "r2d2_tutorial.urdf").read_bytes())
    # a plain URDF passes through untouched, as bytes
    description = load_description(GOOD / "r2d2_tutorial.urdf")
    assert description.text == (GOOD / "r2d2_tutorial.urdf").read_bytes()


# --------------------------------------------------------------------------- errors


def write(tmp_path: Path, body: str, name: str = "robot.urdf.xacro") -> Path:
    path = tmp_path / name
    head = '<?xml version="1.0"?>\n<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r">'
    path.write_text(f"{head}\n{body}\n</robot>\n")
    return path


def refusal(path: Path, **kwargs: object) -> str:
    with pytest.raises(XacroError) as info:
        load_description(path, **kwargs)  # type: ignore[arg-type]
    message = str(info.value)
    assert isinstance(info.value, UrdfError)
    assert "\n" not in message and len(message) < 1200
    return message


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


# --------------------------------------------------------------------------- hostile files

# Each payload creates MARKER when it runs. The first three run shell commands with plain xacro 2.1
# (test_payloads_are_real_escapes_with_plain_xacro shows it); the others are variations.
ESCAPES = {
    # a running generator's frame leads to xacro's module globals, then os.system
    "generator_frames": '<link name="${[L := [], g := (q.gi_frame.f_back.f_back.f_globals for q in L), '
    "L.append(g), python.list(g)][-1][0]['os'].system('touch MARKER')}\"/>",
    # python.vars + python.type and dunder names built from strings: object's subclasses, os._wrap_close,
    # its __init__'s globals through the __globals__ descriptor's __get__ slot wrapper
    "vars_and_built_dunders": '<link name="${[O := python.type(0).mro()[-1], '
    "W := [c for c in python.vars(python.type(O))['_'+'_subclasses__'](O) "
    "if python.vars(c).get('_'+'_module__') == 'os' and 'close' in python.vars(c)][0], "
    "f := python.vars(W)['_'+'_init__'], d := python.vars(python.type(f))['_'+'_globals__'], "
    "G := python.vars(python.type(d))['_'+'_get__'](d, f), G['system']('touch MARKER')][-1]}\"/>",
    # $(eval) runs with Python's builtins in plain xacro; a property hides the ')' from xacro's lexer
    "eval_exec": '<xacro:property name="code" value="exec(\'import os; os.system(&quot;touch MARKER&quot;)\', {})"/>'
    '<link name="$(eval ${code})"/>',
}
VARIANTS = {
    "dunder_attribute": "<link name=\"${''.__class__.__mro__[1]}\"/>",
    "eval_import": "<xacro:property name=\"code\" value=\"__import__('os').system('touch MARKER')\"/>"
    '<link name="$(eval ${code})"/>',
    "eval_open": '<xacro:property name="code" value="open(\'MARKER\', \'w\')"/><link name="$(eval ${code})"/>',
    "getattr": "<link name=\"${getattr(python, 'vars')}\"/>",
    # a format template from a property (not an expression constant) reads dunder attributes
    "property_format": '<xacro:property name="fmt" value="{0.__class__.__mro__}"/><link name="${fmt.format(1)}"/>',
    "lambda_default": '<link name="${(lambda v=python.vars: v)()(python)}"/>',
    "lambda_frame": '<link name="${[(lambda: q.gi_frame) for q in [(x for x in [0])]][0]().f_globals}"/>',
    "type_call": '<link name="${python.type(1)}"/>',
    "vars_direct": '<link name="${python.vars(python)}"/>',
    "eval_frames": '<xacro:property name="code" value="[(x for x in [0])][0].gi_frame.f_globals"/>'
    '<link name="$(eval ${code})"/>',
}


@pytest.mark.parametrize("name", sorted(ESCAPES))
def test_payloads_are_real_escapes_with_plain_xacro(tmp_path: Path, name: str) -> None:
    path = write(tmp_path, ESCAPES[name].replace("MARKER", str(tmp_path / "PWNED")))
    plain = plain_xacro(tmp_path, path, {}, {})
    plain.communicate(timeout=60)
    assert (tmp_path / "PWNED").exists()  # the control: this payload does run a command with plain xacro


@pytest.mark.parametrize("name", sorted({**ESCAPES, **VARIANTS}))
def test_hostile_expressions_run_nothing(tmp_path: Path, name: str) -> None:
    payload = {**ESCAPES, **VARIANTS}[name]
    path = write(tmp_path, payload.replace("MARKER", str(tmp_path / "PWNED")))
    message = refusal(path)
    assert not (tmp_path / "PWNED").exists()
    assert message.startswith("robot.urdf.xacro: ")
    if name not in ("eval_import",):  # xacro itself refuses '__' in $(eval) first
        assert "refused for safety" in message or "is not defined" in message, message


def test_refusal_message_says_what_was_refused(tmp_path: Path) -> None:
    message = refusal(write(tmp_path, VARIANTS["vars_direct"]))
    assert message == "robot.urdf.xacro: expression refused for safety: attribute 'vars' is not allowed"
    message = refusal(write(tmp_path, ESCAPES["eval_exec"].replace("MARKER", "x")))
    assert message == "robot.urdf.xacro: expression refused for safety: name 'exec' is not allowed"


def test_ordinary_expressions_still_work(tmp_path: Path) -> None:
    (tmp_path / "conf.yaml").write_text("arm: {length: 0.5, names: [a, b]}\nangle: !degrees 90\n")
    path = write(
        tmp_path,
        '<xacro:property name="conf" value="${xacro.load_yaml(\'conf.yaml\')}"/>'
        '<xacro:arg name="side" default="left"/>'
        "<link name=\"${'%s_%s' % ('$(arg side)', conf.arm.names[1])}\"/>"
        '<link name="l_${conf.arm.length * 2}_${round(conf.angle, 4)}_${python.sorted([3, 1])[0]}"/>'
        '<xacro:property name="e" value="arg(\'side\') + \'_\' + str(int(pi))"/><link name="$(eval ${e})"/>'
        '<link name="${math.radians(180) == pi and (lambda x: x + 1)(1)}"/>'
        '<xacro:property name="type" value="revolute"/><link name="${type}"/>',
    )
    urdf = expand_xacro(path, mappings={"side": "right"}, packages=PackageIndex())
    names = [el.get("name") for el in etree.fromstring(urdf.encode())]
    assert names == ["right_b", "l_1.0_1.5708_1", "right_3", "2", "revolute"]


def test_include_of_a_device_or_an_entity_bomb_is_refused(tmp_path: Path) -> None:
    message = refusal(write(tmp_path, '<xacro:include filename="/dev/zero"/>'))
    assert message.startswith("zero: is not a regular file; refused")
    (tmp_path / "bomb.xacro").write_text(
        '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">]>'
        "<robot>&b;</robot>"
    )
    assert "declares entities" in refusal(write(tmp_path, '<xacro:include filename="bomb.xacro"/>'))


def test_runaway_recursion_and_output_are_bounded(tmp_path: Path) -> None:
    path = write(tmp_path, '<xacro:macro name="m" params=""><xacro:m/></xacro:macro><xacro:m/>')
    assert "nest too deeply" in refusal(path)
    path = write(tmp_path, "<link name=\"${'x' * (70 * 1024 * 1024)}\"/>")
    assert "expands to more than 67108864 bytes; refused" in refusal(path)


def test_runaway_memory_is_bounded(tmp_path: Path) -> None:
    message = refusal(write(tmp_path, '<link name="${len([0] * (1024**3))}"/>'))
    assert message == "robot.urdf.xacro: xacro ran out of memory (limit 2048 MiB)"


def test_a_slow_expression_is_stopped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(xacro_load, "TIMEOUT_S", 2.0)
    message = refusal(write(tmp_path, '<link name="${9**9**9}"/>'))
    assert message == "robot.urdf.xacro: xacro expansion took more than 2 s; stopped"


def test_hooks_are_restored_after_expansion() -> None:
    import xacro
    from xacro import substitution_args

    before = (xacro.safe_eval, xacro.parse, xacro._global_symbols, substitution_args._eval)
    with xacro_load._hardened(PackageIndex()):
        assert xacro.safe_eval is not before[0]
        assert "vars" not in xacro._global_symbols["python"]
    assert (xacro.safe_eval, xacro.parse, xacro._global_symbols, substitution_args._eval) == before


def test_data_readme_lists_every_repository() -> None:
    readme = (XACRO / "README.md").read_text()
    for folder in XACRO.iterdir():
        if folder.is_dir():
            assert f"`{folder.name}/`" in readme, folder.name
            assert any(folder.glob("LICENSE*")) or f"`{folder.name}/` has no licence file" in readme
