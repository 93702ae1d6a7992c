"""What a xacro expression may do: arithmetic, names, yaml lookups — nothing that reaches Python's insides.

A xacro file is a program: ``${…}`` and ``$(eval …)`` are Python expressions. Plain xacro blocks names
starting with ``__`` only, so known escapes still run shell commands: reaching ``os`` through
``python.vars(...)`` and a dunder key built from strings, through a generator's frame
(``(x for x in ()).gi_frame.f_back.f_globals``), or ``$(eval exec(...))`` (xacro's ``$(eval)`` runs with
Python's builtins). :func:`check_expression` refuses, before anything is evaluated:

- names and attributes starting with ``_``; string constants containing ``__``;
- reflection helpers (:data:`BANNED_NAMES`), also as attributes (``python.vars``), and calls to I/O and
  introspection builtins (:data:`BANNED_CALLS`);
- attributes that lead to frames, code or globals (:data:`BANNED_ATTRIBUTES`), and ``str.format`` unless
  its template is a literal whose fields read no attribute or item (``'{}_link'.format(p)`` is fine).

Without ``getattr``, ``vars``, ``type``, ``format`` and underscores, a string built at run time (``'__cla' +
'ss__'``) names nothing. :mod:`r2d2_viz.robot.xacro_load` also shrinks the namespaces and runs ``$(eval)``
without builtins, so these checks are one layer of two.
"""

from __future__ import annotations

import ast
import string

BANNED_NAMES = frozenset(
    {
        "getattr", "setattr", "delattr", "vars", "globals", "locals", "eval", "exec", "compile", "breakpoint",
        "memoryview", "super", "classmethod", "staticmethod",
    }
)  # fmt: skip
"""Refused wherever they appear (as a name or an attribute)."""
BANNED_CALLS = frozenset(
    {
        "type", "dir", "id", "open", "input", "help", "object", "property", "print", "exit", "quit", "hasattr",
        "license", "credits", "copyright",
    }
)  # fmt: skip
"""Refused when called or read as an attribute (``python.type``); as plain names they are common macro
parameters (``type``, ``id``) whose values are harmless."""
BANNED_ATTRIBUTES = frozenset(
    {
        "format", "format_map", "mro", "gi_frame", "gi_code", "gi_yieldfrom", "cr_frame", "cr_code",
        "cr_await", "ag_frame", "ag_code", "ag_await", "f_back", "f_globals", "f_locals", "f_builtins",
        "f_code", "tb_frame", "tb_next", "func_globals", "func_code", "co_code", "im_func", "im_self",
    }
)  # fmt: skip
MAX_EXPRESSION_CHARS = 100_000


class RefusedExpressionError(ValueError):
    """An expression that could reach Python's insides; the message says which part."""


def check_expression(expression: str) -> None:
    """Raise :class:`RefusedExpressionError` if ``expression`` (one ``${…}`` or ``$(eval …)`` body) may do more
    than compute a value; let a :class:`SyntaxError` through for xacro to report."""
    if len(expression) > MAX_EXPRESSION_CHARS:
        raise RefusedExpressionError(f"expression is longer than {MAX_EXPRESSION_CHARS} characters")
    tree = ast.parse(expression.strip(), mode="eval")
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            _check_name(node.id, "name")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in BANNED_CALLS:
            raise RefusedExpressionError(f"calling {node.func.id!r} is not allowed")
        elif isinstance(node, ast.NamedExpr):
            raise RefusedExpressionError("assignment expressions (:=) are not allowed")
        elif isinstance(node, ast.Attribute):
            _check_name(node.attr, "attribute")
            if node.attr in BANNED_CALLS or (node.attr in BANNED_ATTRIBUTES and not _plain_format(node)):
                raise RefusedExpressionError(f"attribute {node.attr!r} is not allowed")
        elif isinstance(node, ast.Constant) and isinstance(node.value, (str, bytes)):
            text = node.value if isinstance(node.value, str) else node.value.decode("latin-1")
            if "__" in text:
                raise RefusedExpressionError(f"string {_short(text)} contains '__'")
        elif isinstance(node, ast.keyword) and node.arg is not None and node.arg.startswith("_"):
            raise RefusedExpressionError(f"keyword {node.arg!r} starts with '_'")
        elif isinstance(node, ast.arg) and node.arg.startswith("_"):
            raise RefusedExpressionError(f"parameter {node.arg!r} starts with '_'")


def _check_name(name: str, kind: str) -> None:
    if name.startswith("_"):
        raise RefusedExpressionError(f"{kind} {name!r} starts with '_'")
    if name in BANNED_NAMES:
        raise RefusedExpressionError(f"{kind} {name!r} is not allowed")


def _plain_format(node: ast.Attribute) -> bool:
    """``'literal'.format(...)`` whose fields are plain (``{}``, ``{0}``, ``{name}``, ``{:.3f}``)."""
    if node.attr != "format" or not isinstance(node.value, ast.Constant) or not isinstance(node.value.value, str):
        return False
    try:
        fields = list(string.Formatter().parse(node.value.value))
    except ValueError:
        return False
    for _, field, spec, _ in fields:
        if field and ("." in field or "[" in field):
            return False
        if spec and "{" in spec:
            return False
    return True


def _short(text: str, limit: int = 40) -> str:
    return repr(text if len(text) <= limit else text[: limit - 1] + "…")
