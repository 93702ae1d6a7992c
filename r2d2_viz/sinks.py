"""Where the recording goes: a spawned viewer, a remote viewer, a served web viewer, a file — or nowhere.

Part of the stream layer (with :mod:`r2d2_viz.stream`, the only modules that import rerun).
"""

from __future__ import annotations

import os
import shutil
import socket
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import rerun as rr

from .blueprint import generate_blueprint
from .errors import SinkError
from .stream import APP_ID

DEFAULT_GRPC_PORT = 9876
DEFAULT_WEB_PORT = 9090


@dataclass(frozen=True)
class SinkConfig:
    spawn: bool = False
    connect: str | None = None
    """gRPC URL of a running viewer (``rerun+http://HOST:PORT/proxy``)."""
    serve: bool = False
    save: Path | None = None
    headless: bool = False
    bind: str = "127.0.0.1"
    port: int = DEFAULT_GRPC_PORT
    web_port: int = DEFAULT_WEB_PORT

    @property
    def live(self) -> bool:
        return self.spawn or self.connect is not None or self.serve


def viewer_executable() -> str | None:
    """The ``rerun`` viewer binary that ships with rerun-sdk (next to this Python), else on PATH."""
    beside = Path(sys.executable).parent / "rerun"
    if beside.is_file() and os.access(beside, os.X_OK):
        return str(beside)
    return shutil.which("rerun")


def _check_port_free(bind: str, port: int, what: str) -> None:
    with socket.socket(socket.AF_INET6 if ":" in bind else socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((bind, port))
        except OSError as exc:
            raise SinkError(f"--serve: cannot listen on {bind}:{port} for the {what}: {exc.strerror}") from None


def open_recording(
    config: SinkConfig,
    *,
    save_to: Path | None = None,
    on_ready: Callable[[str], None] | None = None,
) -> rr.RecordingStream:
    """A recording stream with the configured sinks and the RViz-like default blueprint.

    ``save_to`` is the file actually written (the caller renames it into place when done).
    """
    blueprint = generate_blueprint()
    if config.headless:
        rec = rr.RecordingStream(APP_ID, default_enabled=False)
        return rec
    rec = rr.RecordingStream(APP_ID, send_properties=True)
    sinks: list[rr.FileSink | rr.GrpcSink | rr.GrpcServerSink] = []
    if config.spawn:
        if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
            raise SinkError("--spawn: no display to open the viewer on; use --save FILE.rrd or --serve instead")
        executable = viewer_executable()
        if executable is None:
            raise SinkError("--spawn: the 'rerun' viewer binary was not found; use --save FILE.rrd or --serve instead")
        try:
            rr.spawn(port=config.port, connect=False, executable_path=executable, recording=rec)
        except Exception as exc:
            raise SinkError(f"--spawn: the viewer did not start ({exc}); use --save FILE.rrd or --serve") from None
        sinks.append(rr.GrpcSink(f"rerun+http://127.0.0.1:{config.port}/proxy"))
    if config.connect is not None:
        sinks.append(rr.GrpcSink(config.connect))
    if config.serve:
        _check_port_free(config.bind, config.port, "gRPC server")
        _check_port_free(config.bind, config.web_port, "web viewer")
        server = rr.GrpcServerSink(bind_ip=config.bind, port=config.port)
        sinks.append(server)
    if save_to is not None:
        sinks.append(rr.FileSink(save_to))
    rec.set_sinks(*sinks, default_blueprint=blueprint)
    if config.serve:
        uri = server.uri
        rr.serve_web_viewer(web_port=config.web_port, open_browser=False, connect_to=uri)
        host = "localhost" if config.bind in ("127.0.0.1", "::1") else config.bind
        url = f"http://{host}:{config.web_port}/?url={uri}"
        if on_ready is not None:
            on_ready(f"serving: open {url} in a browser, or run: rerun {uri}")
    return rec


def close_recording(rec: rr.RecordingStream) -> None:
    """Flush everything to the sinks and close them (finalises an .rrd file)."""
    rec.flush()
    rec.disconnect()
