"""The house rules of the code (issues 9 and 17): public APIs of the dependencies only, small modules and classes,
subpackages by pipeline stage that import only the stages below them, rerun only in the viewer, tests that mirror
the layout."""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

import pytest
from conftest import REPO

PACKAGE = REPO / "r2d2_viz"
MODULES = sorted(p for p in PACKAGE.rglob("*.py") if "assets" not in p.parts)
NO_BEHAVIOUR = ("__init__.py", "__main__.py", "arrays.py", "blueprint.py")
"""Modules with nothing to test on their own: the packages' docstrings and the top package's lazy exports
(tests/test_api.py checks them), the ``python -m`` entries, type aliases."""
PRIVATE_APIS = re.compile(r"rerun_bindings|to_native\(|_parse_robot|\._inner\b")

STAGES = ("robot", "meshes", "kinematics", "msgs", "sources", "rviz", "viewer", "ros_out", "export")
"""The pipeline's stages, in order: each may import only the ones before it (and the base modules)."""
BASE = ("errors", "arrays")
"""Modules every stage may import."""
TOP = (
    "signals",
    "pacing",
    "progress",
    "live_output",
    "live_run",
    "runner",
    "api",
    "cli",
    "blueprint",
    "__init__",
    "__main__",
    "fleet",
    "run",
)
"""The top: it may import every stage. ``fleet/`` (issue 25) is a subpackage that lives here, not a stage: it
calls the runner once per bag, so it sits above everything (and the CLI calls it)."""
TOP_PACKAGES = ("fleet", "cli", "run")
"""Subpackages at the top (beside runner and api), not stages of the pipeline: the fleet, and the command line."""
RERUN_STAGES = ("viewer",)


def _rel(path: Path) -> str:
    return path.relative_to(REPO).as_posix()


def _stage(module: str) -> str:
    """``r2d2_viz.sources.bags.bag`` → ``sources``; a top-level module → its own name."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> list[str]:
    """Every r2d2_viz module ``path`` imports (at the top or inside functions)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            if node.level:
                raise AssertionError(f"{_rel(path)}: relative import (use absolute r2d2_viz.… imports)")
            if node.module.startswith("r2d2_viz"):
                out.append(node.module)
        elif isinstance(node, ast.Import):
            out += [a.name for a in node.names if a.name.startswith("r2d2_viz")]
    return out


@pytest.mark.parametrize("module", MODULES, ids=_rel)
def test_public_apis_only(module) -> None:
    assert not PRIVATE_APIS.findall(module.read_text())


@pytest.mark.parametrize("module", MODULES, ids=_rel)
def test_modules_under_400_lines_and_classes_under_200(module) -> None:
    text = module.read_text()
    assert len(text.splitlines()) <= 400
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ClassDef):
            assert node.end_lineno is not None and node.end_lineno - node.lineno + 1 <= 200, node.name


def test_every_module_has_its_test_file_in_the_mirrored_folder() -> None:
    missing = [
        _rel(m)
        for m in MODULES
        if m.name not in NO_BEHAVIOUR
        and not (REPO / "tests" / m.parent.relative_to(PACKAGE) / f"test_{m.stem}.py").exists()
    ]
    assert not missing


def test_stages_are_subpackages_with_a_docstring_and_few_modules() -> None:
    top = [p.name for p in PACKAGE.glob("*.py")]
    assert len(top) <= 12, top
    packages = [p for p in PACKAGE.rglob("__init__.py") if "assets" not in p.parts]
    for init in packages:
        if init.parent == PACKAGE:
            continue  # the top package's docstring lists the stages
        doc = ast.get_docstring(ast.parse(init.read_text()))
        assert doc and 1 <= len(doc.splitlines()) <= 4, f"{_rel(init)}: a two- or three-line docstring"
        assert len(list(init.parent.glob("*.py"))) - 1 <= 15, _rel(init.parent)
    subpackages = {_stage(_module_name(p.parent / "x.py")) for p in packages if p.parent != PACKAGE}
    assert subpackages == {*STAGES, *TOP_PACKAGES}


def test_every_subpackage_is_installed() -> None:
    listed = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {_module_name(p) for p in PACKAGE.rglob("__init__.py") if "assets" not in p.parts}
    assert found <= listed, found - listed


@pytest.mark.parametrize("module", MODULES, ids=_rel)
def test_a_stage_imports_only_the_stages_below_it(module) -> None:
    mine = _stage(_module_name(module))
    if mine in STAGES:
        allowed = {*STAGES[: STAGES.index(mine) + 1], *BASE}
    elif mine in BASE:
        allowed = set(BASE)
    else:  # the top: runner, api, cli, the package itself
        allowed = {*STAGES, *BASE, *TOP, ""}
    wrong = [i for i in _imports(module) if _stage(i) not in allowed]
    assert not wrong, f"{_rel(module)} imports {wrong}"


def test_no_import_circles() -> None:
    graph = {_module_name(m): set(_imports(m)) for m in MODULES}
    state: dict[str, int] = {}

    def visit(name: str, trail: tuple[str, ...]) -> None:
        if state.get(name) == 2 or name not in graph:
            return
        assert state.get(name) != 1, " → ".join((*trail, name))
        state[name] = 1
        for dep in graph[name]:
            if dep != "r2d2_viz":  # the top package's lazy exports
                visit(dep, (*trail, name))
        state[name] = 2

    for name in graph:
        visit(name, ())


@pytest.mark.parametrize("module", MODULES, ids=_rel)
def test_only_the_viewer_imports_rerun(module) -> None:
    if _stage(_module_name(module)) in RERUN_STAGES:
        return
    tree = ast.parse(module.read_text())
    type_only = {
        id(n)
        for block in ast.walk(tree)
        if isinstance(block, ast.If) and ast.unparse(block.test) == "TYPE_CHECKING"
        for n in ast.walk(block)
    }
    for node in ast.walk(tree):
        if id(node) in type_only:
            continue
        names = (
            [a.name for a in node.names]
            if isinstance(node, ast.Import)
            else [node.module or ""]
            if isinstance(node, ast.ImportFrom)
            else []
        )
        assert not any(n == "rerun" or n.startswith("rerun.") for n in names), _rel(module)
