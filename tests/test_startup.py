"""Issue 17: a plain run imports only what it needs — the real CLI entry in a fresh interpreter, its modules read
from ``sys.modules`` after the run."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from conftest import REPO

AFTER_A_RUN = """
import json, sys
from r2d2_viz.cli import main
code = main(sys.argv[1:])
print(json.dumps(sorted(sys.modules)))
sys.exit(code)
"""
NOT_FOR_A_GENERATED_MOTION = (
    "rosbags",  # bags
    "ruamel",
    "lz4",
    "backports.zstd",
    "yaml",  # --rviz only
    "xacro",  # xacro descriptions only (expanded in a child process)
    "trimesh",  # mesh conversion only
    "collada",
    "pyarrow.compute",  # 60 ms that nothing of a run needs
    "yourdfpy",
    "scipy",
    "av",  # --video only
)


def _modules_after(*args: str) -> set[str]:
    result = subprocess.run(
        [sys.executable, "-c", AFTER_A_RUN, *args], capture_output=True, text=True, timeout=120, check=True
    )
    return set(json.loads(result.stdout.splitlines()[-1]))


def _loaded(modules: set[str], name: str) -> bool:
    return any(m == name or m.startswith(name + ".") for m in modules)


def test_a_plain_save_imports_no_bag_yaml_xacro_or_mesh_converter(tmp_path: Path) -> None:
    modules = _modules_after("--save", str(tmp_path / "run.rrd"), "--duration", "1")
    assert "rerun" in modules and "r2d2_viz.viewer.stream" in modules  # it did run
    assert [name for name in NOT_FOR_A_GENERATED_MOTION if _loaded(modules, name)] == []


NOT_FOR_A_SAVED_BAG = (
    "http.server",  # issue 48: the page's server only when a page is served (~15 ms of a bag run's start-up)
    "email",
    "r2d2_viz.viewer.web.server",
    "r2d2_viz.viewer.web.feed",
)


def test_a_bag_saved_to_a_file_imports_no_page_server(tmp_path: Path) -> None:
    bag = str(REPO / "tests" / "data" / "bags" / "talker_mcap")
    modules = _modules_after("--bag", bag, "--save", str(tmp_path / "run.rrd"))
    assert "r2d2_viz.sources.bags.bag" in modules and "rerun" in modules  # it did read the bag into a recording
    assert [name for name in NOT_FOR_A_SAVED_BAG if _loaded(modules, name)] == []


def test_an_rviz_config_brings_its_yaml_parser(tmp_path: Path) -> None:
    # the counter-check: the same probe does see a module a run needs
    config = REPO / "tests" / "data" / "rviz" / "turtlebot3_model.rviz"
    modules = _modules_after("--rviz", str(config), "--save", str(tmp_path / "run.rrd"), "--duration", "1")
    assert _loaded(modules, "yaml")


def test_listing_a_bag_or_printing_its_tf_tree_imports_no_rerun() -> None:
    """``--list`` and a printed ``--tf-tree`` write text, not a recording: no ``rerun`` (0.6 of the 1.0 s of CPU
    such a run cost when the CLI imported it first; the suite runs them dozens of times)."""
    bag = str(REPO / "tests" / "data" / "bags" / "talker_mcap")
    for args in (["--bag", bag, "--list"], ["--bag", bag, "--tf-tree"]):
        modules = _modules_after(*args)
        assert "r2d2_viz.sources.bags.bag" in modules and not _loaded(modules, "rerun"), args  # it read the bag
