"""Where the page's files come from: our page (package data beside this module) and Rerun's web viewer, the ES
module and wasm that PyPI's ``rerun-notebook`` ships (found without importing it: its package imports Jupyter).

The wasm (67 MB) is sent gzip-compressed: compressed once per rerun-notebook version into the user's cache
(``${XDG_CACHE_HOME:-~/.cache}/r2d2-viz/web``, written under a temporary name and renamed into place).
"""

from __future__ import annotations

import gzip
import hashlib
import importlib.util
import os
import shutil
import tempfile
from pathlib import Path

from r2d2_viz.errors import SinkError

HERE = Path(__file__).resolve().parent
PAGE_FILES = ("page.html", "page.js", "page.css", "sliders.js")
VIEWER_FILES = ("widget.js", "widget.css")
WASM = "re_viewer_bg.wasm"
GZIP_LEVEL = 6
"""67 MB → 17 MB in about 3 s, once per version; level 9 saves 3 % for three times the time."""


def viewer_static() -> Path:
    """rerun-notebook's ``static`` folder (widget.js, re_viewer_bg.wasm); SinkError naming the extra if missing."""
    spec = importlib.util.find_spec("rerun_notebook")
    folders = list(spec.submodule_search_locations or []) if spec is not None else []
    for folder in folders:
        static = Path(folder) / "static"
        if (static / WASM).is_file() and all((static / name).is_file() for name in VIEWER_FILES):
            return static
    raise SinkError("--serve: Rerun's web viewer (rerun-notebook) is not installed: reinstall r2d2-viz")


FOLLOW_PATCH = (
    'play_state: msg.play ? "playing" : "paused"',
    'play_state: msg.play === "following" ? "following" : msg.play ? "playing" : "paused"',
)
"""widget.js's time control, taught to follow the latest data, as the viewer does for a gRPC stream: an HTTP
``.rrd`` opens playing from its start (the page asks for ``following`` when the recording opens)."""


def widget_js(static: Path) -> bytes:
    """rerun-notebook's widget.js with :data:`FOLLOW_PATCH` (unchanged if that line is not there)."""
    text = (static / "widget.js").read_text(encoding="utf-8")
    return text.replace(*FOLLOW_PATCH, 1).encode()


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "r2d2-viz" / "web"


def compressed_wasm(static: Path, cache: Path | None = None) -> Path:
    """The gzip of ``static``'s wasm, made once and kept (named by the wasm's size and modification time)."""
    wasm = static / WASM
    stat = wasm.stat()
    key = hashlib.sha256(f"{wasm.resolve()}:{stat.st_size}:{stat.st_mtime_ns}".encode()).hexdigest()[:16]
    folder = cache or cache_dir()
    target = folder / f"re_viewer_bg-{key}.wasm.gz"
    if target.is_file():
        return target
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".wasm-", suffix=".gz.tmp")
    try:
        with os.fdopen(fd, "wb") as raw, gzip.GzipFile(fileobj=raw, mode="wb", compresslevel=GZIP_LEVEL, mtime=0) as gz:
            with wasm.open("rb") as source:
                shutil.copyfileobj(source, gz, 1 << 20)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target
