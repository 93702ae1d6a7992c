"""A :class:`~.tf_tree.TfTree` in words and as a graph: the text ``--tf-tree`` prints (each frame on its own line
under its parent, ``static`` or its rate and largest gap; then the problems, one line each) and graphviz's dot
text (``--tf-tree FILE.dot``; ``FILE.svg`` through graphviz's ``dot`` where it is installed). Pure."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

from r2d2_viz.errors import UsageError, shown_in_line
from r2d2_viz.sources.system.tf_tree import Edge, TfTree

GRAPH_SUFFIXES = (".dot", ".gv", ".svg")


def edge_text(edge: Edge) -> str:
    """``static``, or ``20 Hz, largest gap 0.061 s`` (a single message: ``1 message``)."""
    if edge.static:
        return "static"
    if edge.rate_hz is None or edge.max_gap_s is None:
        return f"{edge.count} message" + ("s" if edge.count != 1 else "") + ", no rate"
    return f"{edge.rate_hz:.4g} Hz, largest gap {edge.max_gap_s:.3g} s"


def tree_lines(tree: TfTree, title: str) -> list[str]:
    """The text: a title line, the frames (depth-first from each root, indented; a frame with two parents under
    each), the frames no root reaches (loops), then the problems."""
    kids: dict[str, list[Edge]] = {}
    for e in tree.edges:
        kids.setdefault(e.parent, []).append(e)
    dynamic = sum(not e.static for e in tree.edges)
    span = (tree.span_ns[1] - tree.span_ns[0]) / 1e9
    roots = len(tree.roots)
    lines = [
        f"{title}: {len(tree.frames)} frames, {dynamic} dynamic and {len(tree.edges) - dynamic} static edges, "
        f"{roots} root{'' if roots == 1 else 's'}, over {span:.3g} s"
    ]
    if not tree.edges:
        lines.append("no transforms (no /tf or /tf_static messages)")
    shown: set[str] = set()
    for root in tree.roots:
        lines.append(f"{root} (root)")
        shown.add(root)
        todo = [(e, 1) for e in reversed(kids.get(root, []))]
        while todo:
            e, depth = todo.pop()
            lines.append(f"{'  ' * depth}{e.child} ← {e.parent}: {edge_text(e)}")
            if e.child in shown:
                continue
            shown.add(e.child)
            todo += [(k, depth + 1) for k in reversed(kids.get(e.child, []))]
    rest = [e for e in tree.edges if e.child not in shown]
    if rest:
        lines.append("frames no root reaches:")
        lines += [f"  {e.child} ← {e.parent}: {edge_text(e)}" for e in rest]
    if tree.problems:
        lines.append(f"problems ({len(tree.problems)}):")
        lines += [f"  {p}" for p in tree.problems]
    else:
        lines.append("problems: none")
    return lines


NOT_XML = re.compile(r"[\ud800-\udfff\ufffe\uffff]")
"""Characters XML 1.0 allows in no document (beside the control characters :func:`shown_in_line` shows)."""


def _quoted(*lines: str) -> str:
    """Names or a label's lines as a dot string that graphviz draws as it reads and writes into valid SVG: control
    characters shown (``\\x00``: XML 1.0 allows none but tab and newline, and a frame named ``&#0;`` … does not
    become NUL either), '&' as ``&amp;`` (graphviz copies a character reference such as ``&#0;`` into its SVG
    as it is, and draws ``&amp;`` as '&'), backslashes doubled (``\\N`` would be the node's name) and quotes
    escaped; the lines joined by line breaks."""
    text = "\n".join(NOT_XML.sub("\ufffd", shown_in_line(line)).replace("&", "&amp;") for line in lines)
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def dot_text(tree: TfTree, title: str) -> str:
    """Graphviz's dot: a box per frame (problem frames red), an arrow per parent → child labelled ``static`` or
    its rate and largest gap (as ``view_frames`` draws it)."""
    out = [
        "digraph tf_tree {",
        f"  label={_quoted(title)};",
        "  rankdir=TB;",
        '  node [shape=box, style="rounded,filled", fillcolor="#eef3fb", fontname="Helvetica"];',
        '  edge [fontname="Helvetica", fontsize=10];',
    ]
    for frame in tree.frames:
        colour = ', color="#c62828", fillcolor="#fde0dc"' if frame in tree.problem_frames else ""
        out.append(f"  {_quoted(frame)} [label={_quoted(frame)}{colour}];")
    for e in tree.edges:
        style = ", style=dashed" if e.static else ""
        out.append(f"  {_quoted(e.parent)} -> {_quoted(e.child)} [label={_quoted(*edge_text(e).split(', '))}{style}];")
    out.append("}")
    return "\n".join(out) + "\n"


def graph_data(tree: TfTree, path: Path, title: str) -> bytes:
    """What ``path`` holds (.dot/.gv: dot text; .svg: drawn by graphviz's ``dot``) — a UsageError for another
    extension or an .svg without graphviz."""
    if path.suffix not in GRAPH_SUFFIXES:
        raise UsageError(f"--tf-tree {path}: unknown extension {path.suffix or '(none)'!r}; write .dot or .svg")
    text = dot_text(tree, title)
    if path.suffix != ".svg":
        return text.encode()
    dot = shutil.which("dot")
    if dot is None:
        raise UsageError(
            f"--tf-tree {path}: drawing an .svg needs graphviz's dot (apt install graphviz); "
            f"--tf-tree {path.with_suffix('.dot')} writes the graph's dot text"
        )
    try:
        done = subprocess.run([dot, "-Tsvg"], input=text.encode(), capture_output=True, timeout=60, check=False)
    except subprocess.TimeoutExpired:
        raise UsageError(f"--tf-tree {path}: graphviz's dot took over 60 s; write .dot instead") from None
    if done.returncode != 0:
        said = " ".join(done.stderr.decode(errors="replace").split())[:200]
        raise UsageError(f"--tf-tree {path}: graphviz's dot failed: {said}")
    return done.stdout
