"""The page's files: Rerun's web viewer found in rerun-notebook without importing it, its wasm gzip-compressed
once into the cache (read back with Python's gzip: the same bytes)."""

from __future__ import annotations

import gzip
import importlib.util
import sys
from pathlib import Path

import pytest

from r2d2_viz.errors import SinkError
from r2d2_viz.viewer.web import assets


def test_the_viewer_is_rerun_notebooks_and_matches_the_sdk() -> None:
    from importlib.metadata import version

    static = assets.viewer_static()
    assert (static / "widget.js").read_text().count("export {") == 1 and (static / assets.WASM).stat().st_size > 1e7
    assert version("rerun-notebook") == version("rerun-sdk")  # pinned to the SDK's version
    assert "rerun_notebook" not in sys.modules  # found, not imported (its package imports Jupyter)


def test_missing_rerun_notebook_says_to_reinstall(monkeypatch: pytest.MonkeyPatch) -> None:
    """rerun-notebook is a dependency of every install: missing, the install is broken."""
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    with pytest.raises(SinkError, match=r"\(rerun-notebook\) is not installed: reinstall r2d2-viz"):
        assets.viewer_static()


def test_the_wasm_is_compressed_once(tmp_path: Path) -> None:
    static = tmp_path / "static"
    static.mkdir()
    data = bytes(range(256)) * 4000 + b"\0" * 100_000
    (static / assets.WASM).write_bytes(data)
    made = assets.compressed_wasm(static, tmp_path / "cache")
    assert gzip.decompress(made.read_bytes()) == data and made.stat().st_size < len(data) / 3
    before = made.stat().st_mtime_ns
    assert assets.compressed_wasm(static, tmp_path / "cache") == made and made.stat().st_mtime_ns == before
    assert [p.name for p in (tmp_path / "cache").iterdir()] == [made.name]  # no temporary file left


def test_the_page_module_parses(tmp_path: Path) -> None:
    """page.js is an ES module: a syntax error leaves the page on "loading the viewer…" for ever (seen: a ``const``
    declared twice in one function). Node's own parser checks it, when Node is installed."""
    import shutil
    import subprocess

    from r2d2_viz.viewer.web.assets import HERE

    node = shutil.which("node")
    if node is None:
        pytest.skip("no node to parse page.js with")
    module = tmp_path / "page.mjs"
    module.write_bytes((HERE / "page.js").read_bytes())
    done = subprocess.run([node, "--check", str(module)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr


def test_the_served_widget_follows_the_latest_data() -> None:
    """rerun-notebook 0.41.0's widget.js has the line the page's follow patch changes (the page asks the viewer
    to follow the recording as it grows, as it does a gRPC stream)."""
    static = assets.viewer_static()
    original = (static / "widget.js").read_text()
    assert original.count(assets.FOLLOW_PATCH[0]) == 1
    assert assets.FOLLOW_PATCH[1].encode() in assets.widget_js(static)
