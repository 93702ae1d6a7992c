"""Tests for the xacro sandbox (r2d2_viz.robot.xacro_sandbox): hostile xacro files run nothing and stay bounded."""

from __future__ import annotations

from pathlib import Path

import pytest
from lxml import etree
from xacro_cases import plain_xacro, refusal, write

from r2d2_viz.robot import xacro_load, xacro_sandbox
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.xacro_load import expand_xacro

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
    with xacro_sandbox._hardened(PackageIndex()):
        assert xacro.safe_eval is not before[0]
        assert "vars" not in xacro._global_symbols["python"]
    assert (xacro.safe_eval, xacro.parse, xacro._global_symbols, substitution_args._eval) == before


def test_find_env_and_optenv_work(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # What a xacro file can still read (README): packages' paths and environment variables.
    monkeypatch.setenv("R2D2_TEST_SIDE", "left")
    pkg = tmp_path / "somewhere"
    pkg.mkdir()
    path = write(
        tmp_path,
        '<link name="$(env R2D2_TEST_SIDE)_$(optenv R2D2_TEST_UNSET fallback)"/>'
        '<link name="$(find my_pkg)"/>'
        "<xacro:property name=\"e\" value=\"find('my_pkg') + '/' + env('R2D2_TEST_SIDE')\"/>"
        '<link name="$(eval ${e})"/>',
    )
    index = PackageIndex.from_args([f"my_pkg={pkg}"], description=path, environ={})
    urdf = expand_xacro(path, mappings={}, packages=index)
    names = [el.get("name") for el in etree.fromstring(urdf.encode())]
    assert names == ["left_fallback", str(pkg), f"{pkg}/left"]
