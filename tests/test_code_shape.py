"""Issue 9's promises about the code itself: public APIs of the dependencies only, small modules and classes."""

from __future__ import annotations

import ast
import re

import pytest
from conftest import REPO

PACKAGE = REPO / "r2d2_viz"
MODULES = sorted(PACKAGE.glob("*.py"))
PRIVATE_APIS = re.compile(r"rerun_bindings|to_native\(|_parse_robot|\._inner\b")


@pytest.mark.parametrize("module", MODULES, ids=lambda p: p.name)
def test_public_apis_only(module) -> None:
    assert not PRIVATE_APIS.findall(module.read_text())


@pytest.mark.parametrize("module", MODULES, ids=lambda p: p.name)
def test_modules_under_400_lines_and_classes_under_200(module) -> None:
    text = module.read_text()
    assert len(text.splitlines()) <= 400
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ClassDef):
            assert node.end_lineno is not None and node.end_lineno - node.lineno + 1 <= 200, node.name


def test_every_module_has_its_test_file() -> None:
    missing = [
        m.name
        for m in MODULES
        if m.name not in ("__init__.py", "__main__.py") and not (REPO / "tests" / f"test_{m.stem}.py").exists()
    ]
    assert not missing
