"""The TF tree in words and as dot text, from a tree written out by hand."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from r2d2_viz.errors import UsageError
from r2d2_viz.sources.system.tf_report import dot_text, edge_text, graph_data, tree_lines
from r2d2_viz.sources.system.tf_tree import Edge, TfTree

TREE = TfTree(
    (
        Edge("map", "odom", False, 101, 0, 5_000_000_000, 20.0, 0.061),
        Edge("odom", "base_link", True),
        Edge("base_link", "laser", False, 1, 0, 0),
        Edge("a", "b", True),
        Edge("b", "a", True),
    ),
    ("map",),
    ("frame a: in a loop: a → b → a (each the parent of the one before)",),
    (0, 5_000_000_000),
    frozenset({"a"}),
)


def test_each_frame_on_its_own_line_under_its_parent() -> None:
    assert tree_lines(TREE, "TF tree of x") == [
        "TF tree of x: 6 frames, 2 dynamic and 3 static edges, 1 root, over 5 s",
        "map (root)",
        "  odom ← map: 20 Hz, largest gap 0.061 s",
        "    base_link ← odom: static",
        "      laser ← base_link: 1 message, no rate",
        "frames no root reaches:",
        "  b ← a: static",
        "  a ← b: static",
        "problems (1):",
        "  frame a: in a loop: a → b → a (each the parent of the one before)",
    ]


def test_edge_words() -> None:
    assert edge_text(Edge("p", "c", False, 3, 0, 2, 1234.5678, 0.00123)) == "1235 Hz, largest gap 0.00123 s"


def test_dot_names_every_frame_and_edge_and_marks_problems() -> None:
    text = dot_text(TREE, 'a "quoted" title')
    assert text.startswith("digraph tf_tree {") and text.endswith("}\n")
    assert 'label="a \\"quoted\\" title";' in text
    assert '"map" -> "odom" [label="20 Hz\nlargest gap 0.061 s"];' in text
    assert '"odom" -> "base_link" [label="static", style=dashed];' in text
    assert '"a" [label="a", color="#c62828", fillcolor="#fde0dc"];' in text
    assert '"map" [label="map"];' in text


def test_graph_data(tmp_path: Path) -> None:
    assert graph_data(TREE, tmp_path / "t.dot", "t") == dot_text(TREE, "t").encode()
    with pytest.raises(UsageError, match=r"t\.png: unknown extension '\.png'"):
        graph_data(TREE, tmp_path / "t.png", "t")
    if shutil.which("dot") is None:
        with pytest.raises(UsageError, match="needs graphviz's dot"):
            graph_data(TREE, tmp_path / "t.svg", "t")
    else:
        assert b"<svg" in graph_data(TREE, tmp_path / "t.svg", "t")
