"""A folder of recordings as one Rerun dataset (``--dataset DIR``): served by Rerun's catalog server, looked at
in the viewer, and summed up (:func:`fleet_summary`).

The dataset is named after the folder. The catalog reads each ``.rrd`` lazily through its footer, keys it by
its recording id, and skips symlinked files (said once here, with their count).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from urllib.parse import quote

import pyarrow as pa

from r2d2_viz.errors import SinkError, UsageError
from r2d2_viz.fleet.summary import summarise
from r2d2_viz.signals import sigterm_raises
from r2d2_viz.viewer.catalog import catalog_server, read_fleet, register_layout, server_url
from r2d2_viz.viewer.sinks import _check_port_free, ends_with_us, viewer_executable

DEFAULT_PORT = 51234
Say = Callable[[str], None]


def dataset_name(directory: Path) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", directory.resolve().name) or "fleet"


def check_dataset_dir(directory: Path, say: Say) -> None:
    if not directory.is_dir():
        raise UsageError(f"--dataset {directory}: not a directory")
    if not os.access(directory, os.R_OK | os.X_OK):
        raise UsageError(f"--dataset {directory}: not readable")
    files = list(directory.glob("*.rrd"))
    links = [p for p in files if p.is_symlink()]
    if links:
        say(f"{directory}: {len(links)} symlinked .rrd file(s) the catalog skips (copy them in): {links[0].name}…")
    if len(files) == len(links):
        raise UsageError(f"--dataset {directory}: no .rrd recordings in it")


def fleet_summary(directory: str | Path) -> pa.Table:
    """One row per recording of ``directory`` (made by ``r2d2-viz --bag … --save-dir``), computed through a
    catalog server of its own on 127.0.0.1 (see :mod:`r2d2_viz.fleet.summary` for the columns)."""
    directory = Path(directory)
    check_dataset_dir(directory, lambda _: None)
    name = dataset_name(directory)
    with catalog_server(directory, name=name) as server:
        return summarise(read_fleet(server, name))


def serve_dataset(
    directory: Path, *, bind: str, port: int, viewer: str, web_port: int, say: Say, stop_after: float | None = None
) -> None:
    """Serve ``directory`` until Ctrl-C (or ``stop_after`` seconds); ``viewer``: spawn, serve or headless."""
    check_dataset_dir(directory, say)
    if viewer == "spawn" and sys.platform.startswith("linux"):
        if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
            raise SinkError("--spawn: no display to open the viewer on; use --serve or --headless instead")
    name = dataset_name(directory)
    with catalog_server(directory, name=name, bind=bind, port=port) as server:
        register_layout(server, name, directory)
        local = server_url(server).replace("0.0.0.0", "127.0.0.1")
        process = _start_viewer(viewer, local, bind=bind, web_port=web_port, say=say)
        say(f"serving dataset {name!r} ({directory}) at {local}; Ctrl-C stops")
        try:
            with sigterm_raises():  # SIGTERM stops it as Ctrl-C does
                deadline = None if stop_after is None else time.monotonic() + stop_after
                while deadline is None or time.monotonic() < deadline:
                    time.sleep(0.2)
        except KeyboardInterrupt:
            pass
        finally:
            if process is not None and process.poll() is None:
                process.terminate()
                try:
                    process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()


def _start_viewer(viewer: str, url: str, *, bind: str, web_port: int, say: Say) -> subprocess.Popen[bytes] | None:
    if viewer == "headless":
        return None
    executable = viewer_executable()
    if executable is None:
        raise SinkError("the 'rerun' viewer binary was not found; use --headless and open the URL yourself")
    if viewer == "spawn":
        command = [executable, url]
    else:
        _check_port_free(bind, web_port, "web viewer")  # else Rerun's viewer dies at once, after we said "serving"
        command = [executable, "--serve-web", "--bind", bind, "--web-viewer-port", str(web_port), url]
        host = "localhost" if bind in ("127.0.0.1", "::1", "0.0.0.0", "::") else bind
        say(f"open http://{host}:{web_port}/?url={quote(url, safe='')} in a browser")
    try:
        return subprocess.Popen(
            command,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=ends_with_us,  # no viewer left holding its port, however the app ends
        )
    except OSError as exc:
        raise SinkError(f"the viewer did not start ({exc.strerror})") from None
