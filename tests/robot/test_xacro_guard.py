"""Tests for the xacro expression guard (r2d2_viz.robot.xacro_guard): what may and may not be evaluated."""

from __future__ import annotations

import pytest

from r2d2_viz.robot.xacro_guard import RefusedExpressionError, check_expression

# Expressions seen in real descriptions (tests/data/xacro: UR, Franka, PR2, KUKA) or in xacro's own docs.
ALLOWED = [
    "pi/2",
    "-M_PI/2 + 0.01",
    "radians(180) * reflect",
    "sec_mesh_files[name][type]",
    "type",  # a macro parameter named type
    "kinematics_parameters['kinematics']['shoulder']['z']",
    "xacro.load_yaml(joint_limits_parameters_file)",
    "config.arm.names[1]",
    "python.sorted([3, 1])[0]",
    "'{}_{}'.format(prefix, 'link')",
    "'{0:.3f}'.format(x)",
    "'%s_link' % prefix",
    "(lambda x: x + 1)(1)",
    "[i * 2 for i in range(3)]",
    "1 if a == 'true' else 0",
    "math.sqrt(2) ** 2",
    "f'{prefix}_joint'",
]
REFUSED = {
    "''.__class__": "attribute '__class__' starts with '_'",
    "__import__('os')": "name '__import__' starts with '_'",
    "_private": "name '_private' starts with '_'",
    "python.vars(python)": "attribute 'vars' is not allowed",
    "vars(python)": "name 'vars' is not allowed",
    "getattr(x, 'y')": "name 'getattr' is not allowed",
    "exec('1')": "name 'exec' is not allowed",
    "eval('1')": "name 'eval' is not allowed",
    "globals()": "name 'globals' is not allowed",
    "python.type(1)": "attribute 'type' is not allowed",
    "type(1)": "calling 'type' is not allowed",
    "open('/etc/passwd')": "calling 'open' is not allowed",
    "x['_' + '_class__']": "string '_class__' contains '__'",
    "x['__cla' 'ss__']": "string '__class__' contains '__'",
    "(x for x in [0]).gi_frame": "attribute 'gi_frame' is not allowed",
    "f.f_back.f_globals": "attribute 'f_globals' is not allowed",
    "fmt.format(1)": "attribute 'format' is not allowed",
    "'{0.real}'.format(1)": "attribute 'format' is not allowed",
    "'{0[x]}'.format(d)": "attribute 'format' is not allowed",
    "'{:{}}'.format(1, 2)": "attribute 'format' is not allowed",
    "str.format_map('{a}', d)": "attribute 'format_map' is not allowed",
    "(g := 1)": "assignment expressions (:=) are not allowed",
    "(lambda _x: _x)(1)": "starts with '_'",
    "dict(_a=1)": "keyword '_a' starts with '_'",
    "int.mro()": "attribute 'mro' is not allowed",
}


@pytest.mark.parametrize("expression", ALLOWED)
def test_ordinary_expressions_pass(expression: str) -> None:
    check_expression(expression)


@pytest.mark.parametrize("expression", sorted(REFUSED))
def test_reaching_python_insides_is_refused(expression: str) -> None:
    with pytest.raises(RefusedExpressionError) as info:
        check_expression(expression)
    assert REFUSED[expression] in str(info.value)


def test_syntax_errors_are_left_to_xacro() -> None:
    with pytest.raises(SyntaxError):
        check_expression("1 +")


def test_huge_expressions_are_refused_before_parsing() -> None:
    with pytest.raises(RefusedExpressionError, match="longer than"):
        check_expression("1+" * 100_000 + "1")
