"""A folder of recordings as one Rerun dataset (``--dataset DIR``): served by Rerun's catalog server, looked at
in the viewer, and summed up (:func:`fleet_summary`).

The dataset is named after the folder. The catalog reads each ``.rrd`` lazily through its footer, keys it by
its recording id, and skips symlinked files (said once here, with their count).
"""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from contextlib import ExitStack
from pathlib import Path

import pyarrow as pa

from r2d2_viz.errors import SinkError, UsageError
from r2d2_viz.fleet.summary import summarise
from r2d2_viz.signals import sigterm_raises
from r2d2_viz.viewer.catalog import catalog_server, read_fleet, register_layout, server_url
from r2d2_viz.viewer.sinks import _check_port_free, ends_with_us, viewer_executable
from r2d2_viz.viewer.web.guard import DatasetGuard

DEFAULT_PORT = 51234
LOOPBACK = "127.0.0.1"
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
    """Serve ``directory`` until Ctrl-C (or ``stop_after`` seconds); ``viewer``: spawn, serve or headless.

    ``serve``: Rerun's catalog and web viewer each on a free loopback port, reached only through the token's
    guard (:mod:`r2d2_viz.viewer.web.guard`) on ``bind:web_port`` (neither of Rerun's servers takes a token)."""
    check_dataset_dir(directory, say)
    if viewer == "spawn" and sys.platform.startswith("linux"):
        if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
            raise SinkError("--spawn: no display to open the viewer on; use --serve or --headless instead")
    name = dataset_name(directory)
    served = viewer == "serve"
    with catalog_server(directory, name=name, bind=LOOPBACK if served else bind, port=0 if served else port) as server:
        register_layout(server, name, directory)
        local = server_url(server).replace("0.0.0.0", "127.0.0.1")
        with ExitStack() as stack:
            if served:
                guard = _start_guard(stack, local, bind=bind, web_port=web_port)
                say(f"open {guard.url()} in a browser (the viewer, on the dataset)")
                where = f"{guard.url()} (behind the token)"
            else:
                stack.callback(_stop, _start_viewer(viewer, local))
                where = local
            say(f"serving dataset {name!r} ({directory}) at {where}; Ctrl-C stops")
            try:
                with sigterm_raises():  # SIGTERM stops it as Ctrl-C does
                    deadline = None if stop_after is None else time.monotonic() + stop_after
                    while deadline is None or time.monotonic() < deadline:
                        time.sleep(0.2)
            except KeyboardInterrupt:
                pass


def _start_guard(stack: ExitStack, catalog: str, *, bind: str, web_port: int) -> DatasetGuard:
    """Rerun's web viewer on a free loopback port, and the token's guard in front of both it and the catalog."""
    _check_port_free(bind, web_port, "web viewer")  # before anything starts, or after we said "serving"
    catalog_port = int(catalog.rsplit(":", 1)[1])
    viewer_port = _free_loopback_port()
    guard = DatasetGuard((LOOPBACK, catalog_port), (LOOPBACK, viewer_port), bind, web_port)
    stack.callback(guard.close)
    public = "rerun+" + guard.url().removesuffix(f"/{guard.token}/")  # the catalog, as the browser reaches it
    command = ["--serve-web", "--bind", LOOPBACK, "--web-viewer-port", str(viewer_port), public]
    process = _start_viewer("serve", "", command=command)
    stack.callback(_stop, process)
    _wait_listening(process, viewer_port)  # the address is printed once it answers, not before
    return guard


def _wait_listening(process: subprocess.Popen[bytes] | None, port: int, timeout_s: float = 60.0) -> None:
    """Until Rerun's web viewer (``process``) accepts connections on the loopback ``port``; one that ended or never
    listens is a :class:`SinkError`."""
    deadline = time.monotonic() + timeout_s
    while process is not None and process.poll() is None and time.monotonic() < deadline:
        try:
            socket.create_connection((LOOPBACK, port), timeout=1.0).close()
            return
        except OSError:
            time.sleep(0.1)
    raise SinkError(f"Rerun's web viewer did not listen on {LOOPBACK}:{port} within {timeout_s:g} s")


def _free_loopback_port() -> int:
    with socket.socket() as s:
        s.bind((LOOPBACK, 0))
        return int(s.getsockname()[1])


def _stop(process: subprocess.Popen[bytes] | None) -> None:
    if process is not None and process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def _start_viewer(viewer: str, url: str, *, command: list[str] | None = None) -> subprocess.Popen[bytes] | None:
    if viewer == "headless":
        return None
    executable = viewer_executable()
    if executable is None:
        raise SinkError("the 'rerun' viewer binary was not found; use --headless and open the URL yourself")
    try:
        return subprocess.Popen(
            [executable, *(command or [url])],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=ends_with_us,  # no viewer left holding its port, however the app ends
        )
    except OSError as exc:
        raise SinkError(f"the viewer did not start ({exc.strerror})") from None
