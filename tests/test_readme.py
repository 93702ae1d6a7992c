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


# Every example command in the README and docs/ runs from a bare clone (issue 44: a TALOS URDF only the test extras
# bring, a bag kept out of the repository): each file it names is one the repository ships, one an earlier command
# of the same page makes or fetches (`--save X`, `git clone URL`, `mv … X`, `pip install`, a script's output), or
# the reader's own, named as such.
FILE_FLAGS = ("--urdf", "--bag", "--rviz", "--dataset")
YOURS = {"my_bag", "bags/*", "run.bag", "robot.urdf", "robot.urdf.xacro", "my_robot.urdf", "my.rviz", "my_robot.rviz",
         "nav.rviz", "CONFIG.rviz", "X", "BAG", "/shared/bags/*"}  # fmt: skip
"""The reader's own files: placeholders (a bag of theirs, their robot, their config)."""


def _example_commands(text: str) -> list[str]:
    """Every shell command of a page (fenced blocks' lines and code spans), ``$ `` and comments dropped, ``&&``
    lists split."""
    lines = [line for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S) for line in block.splitlines()]
    lines += re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S))
    parts = (part.split(" #")[0].strip() for line in lines for part in line.removeprefix("$ ").split("&&"))
    return [part for part in parts if part]


def _values(words: list[str], flags: tuple[str, ...]) -> list[str]:
    """The values of ``flags`` in a command's words (``--bag`` takes several)."""
    values, flag = [], None
    for word in words[1:]:
        if word.startswith("--"):
            flag = word if word in flags else None
        elif flag is not None:
            values.append(word)
            flag = flag if flag == "--bag" else None
    return values


def _got(name: str, commands: list[str]) -> bool:
    """Whether a command of the page fetches or makes ``name`` (its first component; ``$VAR/…``: VAR set beside an
    install)."""
    head = name.split("/")[0]
    if head.startswith("$"):
        setting = f"{head[1:]}="
        return any(c.startswith(setting) for c in commands) and any("pip install" in c for c in commands)
    for words in (c.split() for c in commands):
        cloned = words[:2] == ["git", "clone"] and words[-1].rstrip("/").rsplit("/", 1)[-1] == head
        moved = words[:1] == ["mv"] and words[-1] == head
        saved = words[:1] == ["r2d2-viz"] and head in (v.rstrip("/") for v in _values(words, ("--save", "--save-dir")))
        scripted = words[:1] in (["python"], ["python3"]) and head in words[2:]
        if cloned or moved or saved or scripted:
            return True
    return False


def test_every_example_command_names_files_a_clone_has_or_gets() -> None:
    missing = []
    for doc in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        commands = _example_commands(doc.read_text())
        for command in commands:
            words = command.split()
            for name in _values(words, FILE_FLAGS) if words[:1] == ["r2d2-viz"] else []:
                if name in YOURS or (REPO / name).exists() or _got(name, commands):
                    continue
                missing.append(f"{doc.name}: {command}: {name}")
    assert not missing, "\n".join(missing)
