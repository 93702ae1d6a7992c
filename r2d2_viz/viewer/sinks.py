"""Where the recording goes: a spawned viewer, a remote viewer, a served web viewer, a file — or nowhere.

Part of the stream layer (with :mod:`r2d2_viz.viewer.stream`, the only modules that import rerun).
"""

from __future__ import annotations

import copy
import importlib.util
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import urlsplit

import rerun as rr
import rerun.blueprint as rrb

from r2d2_viz.errors import DEBUG_ENV, ListenError, SinkError, UsageError, one_line
from r2d2_viz.robot.children import die_with_parent
from r2d2_viz.viewer.entities import APP_ID
from r2d2_viz.viewer.files.whole import flush_file

if TYPE_CHECKING:  # the page's server (http.server, email: ~15 ms idle) only for a run that serves a page
    from r2d2_viz.viewer.web.feed import RecordingFeed
    from r2d2_viz.viewer.web.server import PageServer

DEFAULT_GRPC_PORT = 9876
DEFAULT_WEB_PORT = 9090
SERVER_START_TIMEOUT_S = 30.0
CONNECT_TIMEOUT_S = 3.0
"""How long ``--connect`` tries the viewer's address before saying no viewer is there (Rerun's own gRPC client
retries for ever, and a run waiting on it ignores Ctrl-C)."""
CLOSE_TIMEOUT_S = 30.0
"""How long closing waits for a live viewer to take the rest of the data."""


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
    recording_id: str | None = None
    """None: a random one (Rerun's default); fleet conversions give each bag its own stable id."""
    properties: tuple[tuple[str, str], ...] = ()
    """Recording properties, ``/__properties/<name>`` text values (what a fleet recording says of its bag)."""
    layout_file: Path | None = None
    """The blueprint also written to this ``.rbl`` (a fleet's: the catalog gives it to its dataset)."""
    page: bool = False
    """r2d2-viz's page beside a native viewer (``--motion sliders --spawn``): its sliders, and a web viewer of the
    native viewer's own gRPC server."""

    @property
    def live(self) -> bool:
        return self.spawn or self.connect is not None or self.serve


def has_display() -> bool:
    """Whether a native window can open here (on Linux: ``DISPLAY`` or ``WAYLAND_DISPLAY`` is set)."""
    return not sys.platform.startswith("linux") or bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def current_recording(recording: rr.RecordingStream | None = None) -> rr.RecordingStream:
    """``recording``, else the caller's current Rerun recording (``rr.init``'s)."""
    rec = recording if recording is not None else rr.get_data_recording()
    if rec is None:
        raise UsageError("no Rerun recording: call rr.init(...) first or pass recording=")
    return rec


def viewer_executable() -> str | None:
    """The ``rerun`` viewer binary that ships with rerun-sdk (rerun_cli's own, not the Python script in front of it:
    a signal to that script ends it and leaves the binary running), else the script next to this Python, else on
    PATH."""
    spec = importlib.util.find_spec("rerun_cli")
    if spec is not None and spec.origin is not None:
        binary = Path(spec.origin).parent / "rerun"
        if binary.is_file() and os.access(binary, os.X_OK):
            return str(binary)
    beside = Path(sys.executable).parent / "rerun"
    if beside.is_file() and os.access(beside, os.X_OK):
        return str(beside)
    return shutil.which("rerun")


def _child_output() -> int | None:
    """Where the Rerun processes we start write their log lines: nowhere, unless ``R2D2_VIZ_DEBUG`` is set."""
    return None if os.environ.get(DEBUG_ENV) else subprocess.DEVNULL


def ends_with_us() -> None:
    """``preexec_fn`` of every process the app starts: it gets SIGTERM when the app ends, however the app ends
    (Linux; SIGKILL included), and SIGINT back at its default (a parent that ignores SIGINT, ``nohup … &``)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    die_with_parent()


def _check_port_free(bind: str, port: int, what: str) -> None:
    with socket.socket(socket.AF_INET6 if ":" in bind else socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((bind, port))
        except OSError as exc:
            raise ListenError(f"--serve: cannot listen on {bind}:{port} for the {what}: {exc.strerror}", port) from None


def open_recording(
    config: SinkConfig,
    *,
    save_to: Path | None = None,
    on_ready: Callable[[str], None] | None = None,
    blueprint: rrb.Blueprint | None = None,
) -> Recording:
    """A recording stream with the configured sinks and ``blueprint`` as its default blueprint.

    ``save_to`` is the file actually written (the caller renames it into place when done). Every file
    gets its footer (the chunk manifest: where every chunk is, so a reader need not scan the file), written
    when the recording is closed, live runs included. Rerun keeps the manifest in memory until then: ~3 kB
    per chunk written (a live run sends a chunk per frame: ~7 MB a minute at 30 Hz, ~95 MB at 1 kHz).
    """
    if config.headless:
        return Recording(rr.RecordingStream(APP_ID, default_enabled=False))
    rec = rr.RecordingStream(APP_ID, recording_id=config.recording_id, send_properties=True)
    for name, value in config.properties:
        rec.send_property(name, rr.AnyValues(value=value))
    sinks: list[rr.FileSink | rr.GrpcSink | rr.BinaryStream] = []
    page: PageServer | None = None
    if config.spawn:
        if not has_display():
            raise SinkError("--spawn: no display to open the viewer on; use --save FILE.rrd or --serve instead")
        sinks.append(rr.GrpcSink(_spawn_viewer(config.port)))
        if config.page and not config.serve:
            from r2d2_viz.viewer.web.server import PageServer

            page = PageServer(None, config.bind, config.web_port)  # the sliders; the native viewer shows the robot
    if config.connect is not None:
        _probe(config.connect)
        sinks.append(rr.GrpcSink(config.connect))
    feed: RecordingFeed | None = None
    if config.serve:
        stream = rr.binary_stream(recording=rec)
        page, feed = serve(config, stream)
        sinks.append(stream)
    if save_to is not None:
        sinks.append(rr.FileSink(save_to, write_footer=True))
    rec.set_sinks(*sinks, default_blueprint=blueprint)
    if feed is not None and blueprint is not None:  # set_sinks gives a binary stream no default blueprint
        rec.send_blueprint(following(blueprint), make_active=True, make_default=True)
    if config.layout_file is not None and blueprint is not None:
        blueprint.save(APP_ID, config.layout_file)
    if config.serve and page is not None and on_ready is not None:
        from r2d2_viz.viewer.web.server import RECORDING

        on_ready(f"serving: open {page.url()} in a browser, or run: rerun {page.url()}{RECORDING}")
    elif page is not None and on_ready is not None:
        on_ready(f"the page with the sliders: open {page.url()} in a browser")
    return Recording(rec, live=config.live, page=page, feed=feed, file=save_to)


def update_blueprint(recording: Recording, blueprint: rrb.Blueprint) -> None:
    """A running recording's new layout (a live graph offered a topic that needs a view after the first was
    planned): the viewer makes it active and the default; a saved ``.rrd`` holds it after the first."""
    if rr.get_application_id(recording=recording.rec) is None:
        return  # a recording that goes nowhere (a live run saved as a bag, --headless): no viewer to lay out
    live = following(blueprint) if recording.feed is not None else blueprint
    recording.rec.send_blueprint(live, make_active=True, make_default=True)


def following(blueprint: rrb.Blueprint) -> rrb.Blueprint:
    """``blueprint`` with a time panel that follows the latest data: the page's viewer opens the recording as an
    HTTP ``.rrd``, which it would play from its start like a file (a gRPC stream it follows by itself)."""
    live = copy.copy(blueprint)
    panel = copy.copy(getattr(blueprint, "time_panel", None)) or rrb.TimePanel()
    panel.play_state = rrb.components.PlayState.Following
    live.time_panel = panel
    return live


def serve_recording(rec: rr.RecordingStream, config: SinkConfig) -> Recording:
    """``rec`` streamed to a served viewer (:func:`serve`) instead of its other sinks (the Python API's page)."""
    stream = rr.binary_stream(recording=rec)
    page, feed = serve(config, stream)
    return Recording(rec, live=True, page=page, feed=feed)


def _spawn_viewer(port: int) -> str:
    """The native viewer, listening on 127.0.0.1 only, detached so it outlives the app (like an RViz window);
    a viewer already listening on that port is reused, as ``rr.spawn`` does. Returns its gRPC URL.

    (``rr.spawn`` starts the viewer without ``--bind``, so it listens on every address.)"""
    url = f"rerun+http://127.0.0.1:{port}/proxy"
    if _listening("127.0.0.1", port):
        return url
    executable = viewer_executable()
    if executable is None:
        raise SinkError("--spawn: the 'rerun' viewer binary was not found; use --save FILE.rrd or --serve instead")
    command = [executable, "--bind", "127.0.0.1", f"--port={port}", "--expect-data-soon"]
    try:
        viewer = subprocess.Popen(
            command,
            stdin=subprocess.DEVNULL,
            stdout=_child_output(),
            stderr=_child_output(),
            start_new_session=True,  # detached: Ctrl-C in the terminal ends the app, not the window
            env={**os.environ, "RERUN_APP_ONLY": "true"},
        )
    except OSError as exc:
        raise SinkError(f"--spawn: the viewer did not start ({exc.strerror}); use --save FILE.rrd or --serve") from None
    deadline = time.monotonic() + SERVER_START_TIMEOUT_S
    while time.monotonic() < deadline and viewer.poll() is None:
        if _listening("127.0.0.1", port):
            return url
        time.sleep(0.05)
    _stop(viewer)
    raise SinkError(f"--spawn: the viewer did not start on 127.0.0.1:{port}; use --save FILE.rrd or --serve instead")


def _probe(url: str) -> None:
    """``--connect URL``: a viewer must be listening at its host and port (tried for a few seconds) — Rerun's
    gRPC sink connects lazily and would retry for ever."""
    try:
        parts = urlsplit(url)
        host, port = parts.hostname, parts.port or DEFAULT_GRPC_PORT
    except ValueError as exc:
        raise SinkError(f"--connect {url}: not a viewer URL ({exc}); expected rerun+http://HOST:PORT/proxy") from None
    if not parts.scheme.startswith("rerun") or not host:
        raise SinkError(f"--connect {url}: not a viewer URL; expected rerun+http://HOST:PORT/proxy")
    try:
        socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        why = "timed out" if isinstance(exc, TimeoutError) else (exc.strerror or type(exc).__name__).lower()
        raise SinkError(
            f"--connect {url}: no viewer at {host}:{port} ({why}); start one there with "
            f"'rerun --port {port}', or use --spawn or --serve"
        ) from None


def _listening(host: str, port: int) -> bool:
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as probe:
        return probe.connect_ex((host, port)) == 0


def serve(config: SinkConfig, stream: rr.BinaryStream) -> tuple[PageServer, RecordingFeed]:
    """r2d2-viz's page (the web viewer with RViz's tools, see :mod:`r2d2_viz.viewer.web`) on ``--bind``, its
    viewer reading the recording from ``stream`` through the page's server, under the page's token.

    (No Rerun gRPC server: it takes no token, and would hand the recording to any local process, and relay what
    any process writes into it to the operator's viewer. The SDK's ``serve_web_viewer`` listens everywhere.)
    """
    from r2d2_viz.viewer.web.assets import viewer_static
    from r2d2_viz.viewer.web.feed import RecordingFeed
    from r2d2_viz.viewer.web.server import PageServer

    viewer_static()  # rerun-notebook is a dependency; a broken install is one line
    feed = RecordingFeed(lambda: stream.read(flush=False))
    try:
        return PageServer(feed, config.bind, config.web_port), feed
    except SinkError:
        feed.close()
        raise


def _stop(process: subprocess.Popen[bytes]) -> None:
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


@dataclass
class Recording:
    """The recording stream, and the server process ``--serve`` started, if any."""

    rec: rr.RecordingStream
    server: subprocess.Popen[bytes] | None = None
    """Kept for callers that start a Rerun process of their own (``--serve`` starts none)."""
    live: bool = False
    """A viewer takes the data (closing waits for it at most ``CLOSE_TIMEOUT_S``)."""
    page: PageServer | None = None
    """``--serve``'s page (the web viewer with RViz's tools), if any."""
    feed: RecordingFeed | None = None
    """What the page's viewer reads (``--serve``)."""
    file: Path | None = None
    """The ``.rrd`` written, if any."""


def close_recording(recording: Recording) -> None:
    """Flush everything to the sinks and close them (finalises an .rrd file); stop the server."""
    try:
        if recording.live:  # a viewer that went away must not hold the app for ever
            try:
                recording.rec.flush(timeout_sec=CLOSE_TIMEOUT_S)
            except (RuntimeError, TimeoutError) as exc:
                raise SinkError(f"the viewer did not take the last data: {one_line(exc)}") from None
        else:
            flush_file(recording.rec, recording.file)  # a file sink that deadlocked on a full disk: not for ever
        recording.rec.disconnect()
    finally:
        if recording.feed is not None:
            recording.feed.close()
        if recording.page is not None:
            recording.page.close()
        if recording.server is not None:
            _stop(recording.server)
