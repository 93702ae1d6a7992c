"""Tests for the hardened URDF reader/validator (r2d2_viz.robot.urdf_check)."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import pytest
from conftest import SHARED_REFERENCE
from lxml import etree
from urdfdata import BAD, BAD_MANIFEST, GOOD

from r2d2_viz.errors import UrdfError
from r2d2_viz.robot.urdf_check import MAX_FILE_BYTES, check_robot, read_urdf_xml, resolve_mesh_path

# Every .urdf file in tests/data/good/ -> fragments of the warnings it must produce (in order).
GOOD_MANIFEST: dict[str, list[str]] = {
    "r2d2_tutorial.urdf": [],
    "names_unicode_spaces.urdf": [],
    "extras_ignored.urdf": [],
    "materials.urdf": [],
    "joint_types.urdf": [],
    "mesh_relative.urdf": [],
    "utf8_bom_doctype.urdf": [],
    "mesh_missing.urdf": ["link 'base': visual #1: mesh file 'meshes/missing.stl' not found; visual skipped"],
    "mesh_package.urdf": [
        "package 'r2d2_description' not found: 1 mesh skipped (1 visual; 1 file); give its folder with "
        "--package-path DIR or --package-path r2d2_description=DIR (looked in the folders above "
    ],
    "mesh_package_empty.urdf": [],
    # urdfdom: "joint limit: no lower, defaults to 0" (logDebug); robot_state_publisher accepts it.
    "limit_without_lower.urdf": ["joint 'j': <limit> has no lower; read as 0, like urdfdom"],
    # urdfdom does not look the mimicked joint up; robot_state_publisher then moves the joint on its own.
    "mimic_unknown_joint.urdf": [
        "joint 'j': <mimic> joint 'ghost' does not exist; ignored: the joint moves on its own"
    ],
    "limits_unlimited.urdf": [],
    "material_undefined.urdf": ["link 'base': visual #1: material 'chrome' is not defined; default colour used"],
}


def load(path: Path) -> list[str]:
    return check_robot(read_urdf_xml(path), source=path.name)


def refusal(path: Path) -> str:
    """Load ``path``, expect a UrdfError, check the one-line format and return the message. Bounds in this file
    are CPU time of the test's own thread (``time.thread_time``), not wall-clock time: a loaded machine does not
    lengthen them, while an expanded entity or a quadratic walk still takes seconds of CPU."""
    started = time.thread_time()
    with pytest.raises(UrdfError) as info:
        load(path)
    assert time.thread_time() - started < 1.0
    message = str(info.value)
    assert "\n" not in message and "\r" not in message and len(message.splitlines()) == 1
    assert message.startswith(f"{path.name}: ")
    return message


def write(tmp_path: Path, body: str, name: str = "robot.urdf") -> Path:
    path = tmp_path / name
    path.write_text(body, encoding="utf-8")
    return path


# --------------------------------------------------------------------------- corpus


def test_corpus_manifests_cover_every_file() -> None:
    assert {p.name for p in BAD.iterdir()} == set(BAD_MANIFEST)
    assert {p.name for p in GOOD.glob("*.urdf")} == set(GOOD_MANIFEST)


@pytest.mark.parametrize("name", sorted(BAD_MANIFEST))
def test_bad_corpus_is_refused_with_a_precise_line(name: str) -> None:
    message = refusal(BAD / name)
    assert BAD_MANIFEST[name] in message


@pytest.mark.parametrize("name", sorted(GOOD_MANIFEST))
def test_good_corpus_loads_with_exactly_the_expected_warnings(name: str) -> None:
    warnings = load(GOOD / name)
    expected = GOOD_MANIFEST[name]
    assert len(warnings) == len(expected), warnings
    for warning, fragment in zip(warnings, expected, strict=True):
        assert warning.startswith(f"{name}: ")
        assert "\n" not in warning
        assert fragment in warning


def test_reference_tutorial_model_passes_without_warnings() -> None:
    reference = SHARED_REFERENCE / "r2d2.urdf"
    if not reference.exists():
        pytest.skip("shared reference copy not present; tests/data/good/r2d2_tutorial.urdf covers it")
    assert load(reference) == []
    root = read_urdf_xml(reference)
    assert [j.get("name") for j in root.findall("joint")] == [
        "leg1connect",
        "leg2connect",
        "tilt",
        "swivel",
        "periscope",
        "boxconnect",
    ]


# --------------------------------------------------------------------------- file access


def test_missing_path(tmp_path: Path) -> None:
    assert "file not found" in refusal(tmp_path / "nope.urdf")


def test_directory(tmp_path: Path) -> None:
    folder = tmp_path / "robot.urdf"
    folder.mkdir()
    assert "is a directory" in refusal(folder)


def test_not_a_regular_file() -> None:
    assert "is not a regular file" in refusal(Path("/dev/zero"))


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root can read a chmod 000 file")
def test_unreadable_file(tmp_path: Path) -> None:
    path = write(tmp_path, (GOOD / "r2d2_tutorial.urdf").read_text())
    path.chmod(0)
    try:
        assert "cannot read file: Permission denied" in refusal(path)
    finally:
        path.chmod(0o644)


def test_too_large_file_is_refused_without_reading_it(tmp_path: Path) -> None:
    path = tmp_path / "huge.urdf"
    with path.open("wb") as fh:  # sparse: instant, takes no disk space
        fh.truncate(MAX_FILE_BYTES + 1)
    assert "file is too large" in refusal(path)


# --------------------------------------------------------------------------- hostile XML


def test_billion_laughs_is_refused_fast() -> None:
    started = time.thread_time()
    message = refusal(BAD / "billion_laughs.urdf")
    assert time.thread_time() - started < 1.0
    assert "lol" not in message


def test_bigger_billion_laughs_is_refused_fast(tmp_path: Path) -> None:
    decls = "".join(f'<!ENTITY e{i} "{("&e" + str(i - 1) + ";") * 50}">' for i in range(1, 40))
    path = write(tmp_path, f'<!DOCTYPE robot [<!ENTITY e0 "ha">{decls}]><robot name="&e39;"><link name="a"/></robot>')
    started = time.thread_time()
    assert "DOCTYPE declares entities" in refusal(path)
    assert time.thread_time() - started < 1.0


def test_external_entities_never_leak_file_content(tmp_path: Path) -> None:
    secret = tmp_path / "secret.txt"
    secret.write_text("root:x:0:0:TOPSECRET-7f3a:/root:/bin/bash\n")
    uri = secret.as_uri()
    decl = f'<!DOCTYPE robot [<!ENTITY xxe SYSTEM "{uri}">]>'
    docs = {
        "xxe_general.urdf": decl + '<robot name="&xxe;"><link name="&xxe;"/></robot>',
        "xxe_text.urdf": decl + '<robot><link name="a">&xxe;</link></robot>',
        "xxe_param.urdf": f'<!DOCTYPE robot [<!ENTITY % p SYSTEM "{uri}"> %p;]><robot><link/></robot>',
        "xxe_external_subset.urdf": f'<!DOCTYPE robot SYSTEM "{uri}"><robot><link>&x;</link></robot>',
    }
    for name, body in docs.items():
        message = refusal(write(tmp_path, body, name))
        assert "TOPSECRET" not in message and "root:x:0" not in message, name
    for name in ("xxe_file.urdf", "xxe_parameter_entity.urdf", "external_dtd_entity_reference.urdf"):
        assert "root:" not in refusal(BAD / name)


def test_external_dtd_without_entity_use_is_not_fetched(tmp_path: Path) -> None:
    dtd = tmp_path / "robot.dtd"
    dtd.write_text('<!ENTITY leak "TOPSECRET"><!ATTLIST link name CDATA "TOPSECRET">')
    path = write(tmp_path, f'<!DOCTYPE robot SYSTEM "{dtd.as_uri()}"><robot><link/></robot>')
    # If the DTD were loaded, its attribute default would name the link.
    assert "link #1: missing name attribute" in refusal(path)


def test_excessive_nesting_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, "<robot>" + "<a>" * 5000 + "</a>" * 5000 + "</robot>")
    assert "not well-formed XML" in refusal(path)


def test_newlines_in_names_and_values_stay_on_one_line(tmp_path: Path) -> None:
    body = '<robot><link name="a&#10;b"/><joint name="j&#13;&#10;k" type="fi&#10;xed"/></robot>'
    message = refusal(write(tmp_path, body))
    assert "joint 'j\\r\\nk': unknown joint type 'fi\\nxed'" in message


def test_huge_attribute_is_shortened_in_message(tmp_path: Path) -> None:
    body = f'<robot><link name="a"/><joint name="j" type="{"x" * 100_000}"/></robot>'
    message = refusal(write(tmp_path, body))
    assert len(message) < 400 and "unknown joint type 'xxxx" in message


def test_multiline_source_name_is_flattened() -> None:
    root = etree.fromstring(b"<robot/>")
    with pytest.raises(UrdfError) as info:
        check_robot(root, source="evil\nname.urdf")
    assert "\n" not in str(info.value) and str(info.value).startswith("evil name.urdf: ")


# --------------------------------------------------------------------------- returned tree


def test_returned_root_has_no_comments_or_processing_instructions() -> None:
    root = read_urdf_xml(GOOD / "extras_ignored.urdf")
    assert root.tag == "robot"
    assert all(isinstance(node.tag, str) for node in root.iter())
    assert [el.get("name") for el in root.findall("link")] == ["base", "wheel"]
    assert root.getroottree().docinfo.URL == str((GOOD / "extras_ignored.urdf").absolute())


def test_non_ascii_names_survive() -> None:
    root = read_urdf_xml(GOOD / "names_unicode_spaces.urdf")
    assert [el.get("name") for el in root.findall("link")] == [
        "base link",
        "arm/upper",
        "Gelenk-ä",
        "手首 🤖",
    ]


def test_check_robot_refuses_a_non_robot_root() -> None:
    with pytest.raises(UrdfError, match=r"^x\.urdf: root: element is <model>; expected <robot>$"):
        check_robot(etree.fromstring(b"<model/>"), source="x.urdf")


# --------------------------------------------------------------------------- scale


def test_chain_of_3000_links_is_accepted_quickly(tmp_path: Path) -> None:
    n = 3000
    parts = ['<robot name="chain">']
    parts += [
        f'<link name="l{i}"><visual><geometry><sphere radius="0.1"/></geometry></visual></link>' for i in range(n)
    ]
    parts += [
        f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/><child link="l{i}"/>'
        f'<origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-1" upper="1"/></joint>'
        for i in range(1, n)
    ]
    parts.append("</robot>")
    path = write(tmp_path, "\n".join(parts))
    started = time.thread_time()
    assert load(path) == []
    assert time.thread_time() - started < 2.0


def test_long_cycle_is_reported_compactly(tmp_path: Path) -> None:
    n = 3000
    links = "".join(f'<link name="l{i}"/>' for i in range(n))
    joints = "".join(
        f'<joint name="j{i}" type="fixed"><parent link="l{i}"/><child link="l{(i + 1) % n}"/></joint>' for i in range(n)
    )
    message = refusal(write(tmp_path, f'<robot name="ring">{links}{joints}</robot>'))
    assert "closes a kinematic loop:" in message and "-> …" in message and len(message) < 400


def test_long_mimic_chain_is_linear(tmp_path: Path) -> None:
    n = 3000
    links = "".join(f'<link name="l{i}"/>' for i in range(n))
    joints = "".join(
        f'<joint name="j{i}" type="continuous"><parent link="l{i - 1}"/><child link="l{i}"/>'
        + (f'<mimic joint="j{i - 1}"/>' if i > 1 else "")
        + "</joint>"
        for i in range(1, n)
    )
    path = write(tmp_path, f"<robot>{links}{joints}</robot>")
    started = time.thread_time()
    assert load(path) == []
    assert time.thread_time() - started < 2.0


# --------------------------------------------------------------------------- meshes


MESH_DOC = '<robot><link name="m"><visual><geometry><mesh filename="{}"/></geometry></visual></link></robot>'


def test_mesh_file_uri_and_absolute_path_resolve(tmp_path: Path) -> None:
    cube = (GOOD / "meshes" / "cube.stl").resolve()
    for filename in (cube.as_uri(), str(cube)):
        assert load(write(tmp_path, MESH_DOC.format(filename))) == []


def test_missing_mesh_file_uri_warns(tmp_path: Path) -> None:
    warnings = load(write(tmp_path, MESH_DOC.format((tmp_path / "gone.stl").as_uri())))
    assert len(warnings) == 1 and "link 'm'" in warnings[0] and "gone.stl" in warnings[0]
    assert warnings[0].endswith("not found; visual skipped")


def test_unsupported_mesh_scheme_warns(tmp_path: Path) -> None:
    warnings = load(write(tmp_path, MESH_DOC.format("https://example.com/m.stl")))
    assert len(warnings) == 1 and "unsupported URI scheme 'https'" in warnings[0]


def test_relative_mesh_resolves_against_the_urdf_directory_not_cwd(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert load(GOOD / "mesh_relative.urdf") == []
    assert resolve_mesh_path("meshes/cube.stl", GOOD) == GOOD / "meshes" / "cube.stl"
    assert resolve_mesh_path("meshes/cube.stl", tmp_path) is None


def test_package_uri_best_effort_finds_an_enclosing_package(tmp_path: Path) -> None:
    package = tmp_path / "r2d2_description"
    (package / "urdf").mkdir(parents=True)
    (package / "meshes").mkdir()
    (package / "meshes" / "dome.stl").write_text("solid x\nendsolid x\n")
    path = write(package / "urdf", MESH_DOC.format("package://r2d2_description/meshes/dome.stl"))
    assert load(path) == []
    found = resolve_mesh_path("package://r2d2_description/meshes/dome.stl", package / "urdf")
    assert found == package / "meshes" / "dome.stl"


def test_explicit_base_dir_overrides_document_url(tmp_path: Path) -> None:
    root = etree.fromstring(MESH_DOC.format("meshes/cube.stl").encode())
    assert check_robot(root, source="s.urdf", base_dir=GOOD) == []
    (warning,) = check_robot(root, source="s.urdf", base_dir=tmp_path)
    assert warning.startswith("s.urdf: link 'm': ") and "mesh file 'meshes/cube.stl' not found" in warning


# --------------------------------------------------------------------------- urdfdom's leniency, in the model


def test_missing_lower_reads_as_zero_like_urdfdom() -> None:
    from r2d2_viz.robot.model import load_urdf

    robot = load_urdf(GOOD / "limit_without_lower.urdf")  # <limit upper="1" .../>
    limit = robot.joint("j").limit
    assert limit is not None and (limit.lower, limit.upper) == (0.0, 1.0)


def test_mimic_of_a_missing_joint_is_dropped_and_the_joint_moves_on_its_own() -> None:
    from r2d2_viz.robot.model import load_urdf

    robot = load_urdf(GOOD / "mimic_unknown_joint.urdf")
    assert robot.joint("j").mimic is None
    assert [j.name for j in robot.actuated_joints] == ["j"]


def test_unlimited_limits_are_kept_as_written() -> None:
    from r2d2_viz.robot.model import load_urdf

    robot = load_urdf(GOOD / "limits_unlimited.urdf")
    bounds = {j.name: (j.limit.lower, j.limit.upper) for j in robot.joints if j.limit is not None}
    assert bounds == {
        "rotor_joint": (-1e16, 1e16),
        "slider_joint": (-math.inf, math.inf),
        "hinge_joint": (-1e300, math.inf),  # 1e999 overflows to inf, as strtod reads it
    }


def test_package_uri_with_empty_package_part_resolves() -> None:
    from r2d2_viz.robot.model import MeshFile, load_urdf

    robot = load_urdf(GOOD / "mesh_package_empty.urdf")
    (shape,) = robot.links[0].visuals
    assert isinstance(shape.geometry, MeshFile) and shape.geometry.path == GOOD / "meshes" / "cube.stl"


TWO_MISSING_PACKAGES = """<robot name="two">
  <link name="base">
    <visual><geometry><mesh filename="package://ghost_description/meshes/base.stl"/></geometry></visual>
    <collision><geometry><mesh filename="package://ghost_description/meshes/base_collision.stl"/></geometry></collision>
  </link>
  <link name="wheel_l">
    <visual><geometry><mesh filename="package://ghost_description/meshes/wheel.dae"/></geometry></visual>
    <collision><geometry><mesh filename="package://ghost_description/meshes/wheel.dae"/></geometry></collision>
  </link>
  <link name="wheel_r">
    <visual><geometry><mesh filename="package:///ghost_description/meshes/wheel.dae"/></geometry></visual>
  </link>
  <link name="lidar">
    <visual><geometry><mesh filename="package://phantom_sensors/meshes/lidar.stl"/></geometry></visual>
    <visual><geometry><mesh filename="meshes/not_here.stl"/></geometry></visual>
  </link>
  <joint name="l" type="continuous"><parent link="base"/><child link="wheel_l"/></joint>
  <joint name="r" type="continuous"><parent link="base"/><child link="wheel_r"/></joint>
  <joint name="s" type="fixed"><parent link="base"/><child link="lidar"/></joint>
</robot>
"""


def test_meshes_of_a_missing_package_are_one_line_per_package(tmp_path: Path) -> None:
    """Counted by hand from the URDF above: ghost_description names 5 mesh shapes (3 visual, 2 collision) in 3
    files (wheel.dae three times, once as package:///); phantom_sensors 1. A missing file outside a package keeps
    its own line."""
    warnings = load(write(tmp_path, TWO_MISSING_PACKAGES, "two.urdf"))
    assert len(warnings) == 3, warnings
    assert warnings[0] == "two.urdf: link 'lidar': visual #2: mesh file 'meshes/not_here.stl' not found; visual skipped"
    assert warnings[1].startswith(
        "two.urdf: package 'ghost_description' not found: 5 meshes skipped (3 visual, 2 collision; 3 files); "
        "give its folder with --package-path DIR or --package-path ghost_description=DIR (looked in the folders above "
    )
    assert warnings[2].startswith(
        "two.urdf: package 'phantom_sensors' not found: 1 mesh skipped (1 visual; 1 file); give its folder with "
        "--package-path DIR or --package-path phantom_sensors=DIR (looked in "
    )
    assert all("\n" not in w for w in warnings)


def test_a_missing_package_is_one_line_on_the_command_line(tmp_path: Path) -> None:
    from conftest import cli

    urdf = write(tmp_path, TWO_MISSING_PACKAGES, "two.urdf")
    result = cli("--urdf", str(urdf), "--save", str(tmp_path / "two.rrd"), "--duration", "0.1", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.startswith("warning: ")]
    assert [line.split(" not found")[0] for line in lines] == [
        "warning: two.urdf: link 'lidar': visual #2: mesh file 'meshes/not_here.stl'",
        "warning: two.urdf: package 'ghost_description'",
        "warning: two.urdf: package 'phantom_sensors'",
    ]
