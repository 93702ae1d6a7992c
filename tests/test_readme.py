"""The README's promises that can drift: its two commands and what CI runs."""

from __future__ import annotations

import re
import tomllib

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
    # and fails when it fails: `set -e` lets an && list that fails short of its last command go on (a lint error
    # once skipped the tests and CI went on to the benchmarks, exit 0)
    after = [line for line in ci[ci.index(_commands()[1]) + 1 :] if not line.startswith("#")]
    assert after[0].startswith("status=$?;") and "exit 1" in after[0]


def test_the_test_command_lints_before_testing() -> None:
    tests = _commands()[1]
    steps = [step.strip() for step in tests.split("&&")]
    lint = [".venv/bin/ruff check .", ".venv/bin/ruff format --check .", ".venv/bin/mypy"]
    assert all(step in steps for step in lint)
    assert max(steps.index(step) for step in lint) < steps.index(".venv/bin/pytest")


# The README is for a new user: short, and whatever it leaves out is one link away (docs/, benchmarks/).
DOCS = [REPO / "README.md", REPO / "benchmarks" / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def test_the_readme_is_short() -> None:
    assert len((REPO / "README.md").read_text().splitlines()) <= 350


def _cells(row: str) -> int:
    # a cell's `|` inside backticks is still a separator in GitHub's tables; none of ours has one
    return len(row.strip().strip("|").split("|"))


def test_every_table_row_has_as_many_cells_as_its_header() -> None:
    # renderers drop the cells beyond the header's (issue 29: rows of 8 cells under a 4-column header)
    for doc in DOCS:
        rows: list[str] = []
        for line in [*doc.read_text().splitlines(), ""]:
            if line.startswith("|"):
                rows.append(line)
                continue
            if rows:
                bad = [row for row in rows if _cells(row) != _cells(rows[0])]
                assert not bad, (doc.name, rows[0], bad[:2])
                rows = []


def _anchor(heading: str) -> str:
    # GitHub's rule: lower case, punctuation but `-` and `_` dropped, spaces to `-`
    text = heading.strip().lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def test_relative_links_reach_a_file_and_its_heading() -> None:
    for doc in DOCS:
        for target in re.findall(r"\]\(([^)\s]+)\)", doc.read_text()):
            if re.match(r"[a-z]+:", target):
                continue
            path, _, anchor = target.partition("#")
            file = (doc.parent / path).resolve() if path else doc
            assert file.exists(), (doc.name, target)
            if anchor and file.suffix == ".md":
                headings = re.findall(r"^#+ (.+)$", file.read_text(), flags=re.MULTILINE)
                assert anchor in {_anchor(h) for h in headings}, (doc.name, target)


def test_skip_reasons_speak_of_what_a_clone_has() -> None:
    # a user's clone never has the developers' ../shared folder: a skip reason says what is missing in their terms
    for test in (REPO / "tests").rglob("*.py"):
        for call in re.findall(r"pytest\.skip\((.*?)\)\n", test.read_text(), flags=re.DOTALL):
            assert "shared" not in call and "SHARED" not in call, (test.name, call)


def test_the_usage_lines_run_after_the_install_line() -> None:
    # issue 36: a newcomer typed `r2d2-viz` after the install line and got "command not found" (and
    # `python -m r2d2_viz` the system Python's ModuleNotFoundError): the venv is not active. Said once, right after
    # the install command, before the first usage line.
    text = (REPO / "README.md").read_text()
    after_install = text.split(_commands()[0], 1)[1]
    assert after_install.index(". .venv/bin/activate") < after_install.index("## Usage")


def test_requires_python_is_rerun_sdks() -> None:
    # issue 36: requires-python said >=3.10 and `pip install .` failed on 3.10; the truth is rerun-sdk's metadata
    from importlib.metadata import metadata

    rerun = metadata("rerun-sdk")["Requires-Python"]
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert project["project"]["requires-python"] == rerun
    version = rerun.removeprefix(">=")
    assert project["tool"]["ruff"]["target-version"] == "py" + version.replace(".", "")
    assert f"Python ≥ {version}," in (REPO / "README.md").read_text()
