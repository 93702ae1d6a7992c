"""The README's promises that can drift: its two commands and what CI runs."""

from __future__ import annotations

import re

from conftest import REPO


def _commands() -> list[str]:
    text = (REPO / "README.md").read_text()
    section = text.split("## Two commands", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```bash\n(.+?)\n```", section)


def test_two_commands_install_and_run() -> None:
    main, tests = _commands()
    assert "pip install ." in main and main.rstrip().endswith("r2d2-viz")
    assert "python3 -m venv" in tests and "pip install '.[test]'" in tests and tests.rstrip().endswith("pytest")


def test_ci_runs_the_readme_test_command_verbatim() -> None:
    ci = (REPO / ".ci" / "run").read_text().splitlines()
    assert _commands()[1] in ci


def test_the_test_command_lints_before_testing() -> None:
    tests = _commands()[1]
    steps = [step.strip() for step in tests.split("&&")]
    lint = [".venv/bin/ruff check .", ".venv/bin/ruff format --check .", ".venv/bin/mypy"]
    assert all(step in steps for step in lint)
    assert max(steps.index(step) for step in lint) < steps.index(".venv/bin/pytest")
