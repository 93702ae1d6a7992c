"""The page's HTTP server: the page, Rerun's web viewer (ES module + gzip-compressed wasm), the recording the
viewer reads (:mod:`~r2d2_viz.viewer.web.feed`) and the tool event endpoint — everything under a per-run secret
token (``http://HOST:PORT/<token>/``, as Jupyter puts its token in the URL), so that neither another local user
nor a web page in the same browser can read the recording or publish to the robot. As Jupyter does, the ``Host``
of every request must be a name the server was bound to (or an IP address: a DNS-rebinding page has neither), and
the ``Origin`` of every POST the page's own.

Threaded and bounded (:mod:`~r2d2_viz.viewer.web.door`): a connection that has not shown the token is dropped
after :data:`~r2d2_viz.viewer.web.door.READ_TIMEOUT_S` or when newer ones need its place; at most
:data:`~r2d2_viz.viewer.web.door.MAX_SERVING` requests with the token at once. The event endpoint takes JSON
bodies of at most :data:`MAX_EVENT_BYTES`, at most :data:`EVENTS_PER_S` a second on average (a burst of
:data:`EVENT_BURST`); the ``eye`` endpoint (the 3D view's eye from the viewer's blueprint, for the pose tools:
:mod:`.eye`) blueprints of at most :data:`~.eye.MAX_BLUEPRINT_BYTES`, under the same rate, read by Rerun in a worker
process (a malformed one is a 400, and cannot end the app); anything else gets 4xx and changes nothing.
"""

from __future__ import annotations

import json
import secrets
import socket
import threading
import time
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler
from pathlib import Path
from typing import Any

from r2d2_viz.errors import ListenError, R2d2VizError, SinkError, ToolEventError, one_line, warn
from r2d2_viz.viewer.web.assets import (
    HERE,
    PAGE_FILES,
    VIEWER_FILES,
    WASM,
    cache_dir,
    compressed_wasm,
    viewer_static,
    widget_js,
)
from r2d2_viz.viewer.web.door import (
    KEEP_ALIVE_S,
    READ_TIMEOUT_S,
    DoorServer,
    allowed_hosts,
    host_allowed,
    origin_allowed,
    peer_gone,
    probe_peer,
)
from r2d2_viz.viewer.web.eye import MAX_BLUEPRINT_BYTES, EyeReader, hooked_widget
from r2d2_viz.viewer.web.feed import RecordingFeed

RECORDING = "recording.rrd"
MAX_EVENT_BYTES = 4096
EVENTS_PER_S = 30.0
"""Teleop sends 10 a second while a key is held; clicks are far rarer."""
EVENT_BURST = 60
TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript", ".css": "text/css", ".wasm": "application/wasm"}

EventHandler = Callable[[dict[str, Any]], str]
"""Takes one tool event (the page's JSON), returns the line the page shows; raises R2d2VizError if refused."""


class RateLimit:
    """A token bucket: ``rate`` events a second, ``burst`` at once; ``clock`` injectable for tests."""

    def __init__(self, rate: float, burst: int, clock: Callable[[], float] = time.monotonic) -> None:
        self.rate, self.burst, self.clock = rate, float(burst), clock
        self.tokens, self.last = float(burst), clock()
        self._lock = threading.Lock()

    def take(self) -> bool:
        with self._lock:
            now = self.clock()
            self.tokens = min(self.burst, self.tokens + (now - self.last) * self.rate)
            self.last = now
            if self.tokens < 1.0:
                return False
            self.tokens -= 1.0
            return True


class _Server(DoorServer):
    page: PageServer


class _Handler(BaseHTTPRequestHandler):
    server: _Server
    protocol_version = "HTTP/1.1"
    timeout = READ_TIMEOUT_S

    def log_message(self, format: str, *args: Any) -> None:  # quiet: the app prints its own lines
        return

    def handle_one_request(self) -> None:
        self.server.waiting(self.connection)
        if getattr(self, "_admitted", False):  # it showed the token: the browser's keep-alive, not a stranger's
            self.connection.settimeout(KEEP_ALIVE_S)
        self._admitted = False
        try:
            super().handle_one_request()
        finally:
            if self._admitted:
                self.server.done()

    def _name(self) -> str | None:
        """The file or endpoint asked for, once the token matched and the request came from a name this server
        answers to (the page's own origin, for a POST); None (and 4xx sent) otherwise."""
        path = self.path.split("?", 1)[0]
        prefix = f"/{self.server.page.token}/"
        if not secrets.compare_digest(path[: len(prefix)].encode(), prefix.encode()):
            self._refuse(HTTPStatus.NOT_FOUND, "not found")
            return None
        host = self.headers.get("Host")
        if not host_allowed(host, self.server.page.hosts):
            self._refuse(HTTPStatus.FORBIDDEN, "not a name of this server: open the address the app printed")
            return None
        if self.command == "POST" and not origin_allowed(self.headers.get("Origin"), host):
            self._refuse(HTTPStatus.FORBIDDEN, "not from this page")
            return None
        self._admitted = self.server.admit(self.connection)
        self.connection.settimeout(self.timeout)
        if not self._admitted:
            self._refuse(HTTPStatus.SERVICE_UNAVAILABLE, "busy")
            return None
        return path[len(prefix) :] or "page.html"

    def _refuse(self, status: HTTPStatus, why: str) -> None:
        self.close_connection = True
        self._reply(status, f"{why}\n".encode(), "text/plain")

    def do_GET(self) -> None:
        name = self._name()
        if name is None:
            return
        page = self.server.page
        if name == "page.html":
            self._reply(HTTPStatus.OK, page.html(), TYPES[".html"])
        elif name in PAGE_FILES:
            self._reply(HTTPStatus.OK, (HERE / name).read_bytes(), TYPES[Path(name).suffix])
        elif name == "widget.js":
            self._reply(HTTPStatus.OK, page.widget, TYPES[".js"])
        elif name in VIEWER_FILES:
            self._reply(HTTPStatus.OK, (page.static / name).read_bytes(), TYPES[Path(name).suffix])
        elif name == WASM:
            wasm, gzipped = page.wasm()
            self._send_file(wasm, TYPES[".wasm"], gzip=gzipped)
        elif name == RECORDING and page.feed is not None:
            self._send_feed(page.feed)
        else:
            self._reply(HTTPStatus.NOT_FOUND, b"not found\n", "text/plain")

    def do_POST(self) -> None:
        name = self._name()
        if name is None:
            return
        if name not in ("event", "eye"):
            self._reply(HTTPStatus.NOT_FOUND, b"not found\n", "text/plain")
            return
        try:
            length = int(self.headers.get("Content-Length", "-1"))
        except ValueError:
            length = -1
        if not 0 <= length <= (MAX_EVENT_BYTES if name == "event" else MAX_BLUEPRINT_BYTES):
            self.close_connection = True
            self._reply(HTTPStatus.REQUEST_ENTITY_TOO_LARGE, b"too large\n", "text/plain")
            return
        body = self.rfile.read(length)
        if not self.server.page.limit.take():
            self._reply(HTTPStatus.TOO_MANY_REQUESTS, b"too many events\n", "text/plain")
            return
        if name == "eye":
            try:
                eye = self.server.page.eyes.read(body)
            except ToolEventError as exc:  # not a blueprint: said to the page only, nothing in the terminal
                self._reply(HTTPStatus.BAD_REQUEST, f"{exc}\n".encode(), "text/plain")
                return
            self._reply(HTTPStatus.OK, json.dumps({"eye": eye}).encode(), "application/json")
            return
        try:
            event = json.loads(body)
            if not isinstance(event, dict):
                raise ValueError("not a JSON object")
        except (ValueError, RecursionError) as exc:  # RecursionError: a few thousand nested '['
            self._reply(HTTPStatus.BAD_REQUEST, f"bad event: {str(exc)[:100]}\n".encode(), "text/plain")
            return
        try:
            line = self.server.page.handle(event)
        except R2d2VizError as exc:
            self._reply(HTTPStatus.BAD_REQUEST, json.dumps({"error": str(exc)}).encode(), "application/json")
            return
        self._reply(HTTPStatus.OK, json.dumps({"line": line}).encode(), "application/json")

    def _headers(self, status: HTTPStatus, content_type: str, length: int) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(length))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")  # the token stays out of other sites' logs

    def _reply(self, status: HTTPStatus, body: bytes, content_type: str) -> None:
        self._headers(status, content_type, len(body))
        self.end_headers()
        self.wfile.write(body)

    def _send_feed(self, feed: RecordingFeed) -> None:
        """The recording, from its first byte, then as it grows: an RRD file Rerun's viewer reads as it comes,
        until the app ends (then the connection closes: the viewer keeps what it has) or the follower leaves (seen
        within :data:`~.feed.WAIT_S` while the recording is idle)."""
        self.close_connection = True
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "application/octet-stream")
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Connection", "close")
        self.end_headers()
        probe_peer(self.connection)  # a follower that vanished without closing is seen too, in about a minute
        for chunk in feed.follow(lambda: peer_gone(self.connection)):  # a gone follower frees its place at once
            self.wfile.write(chunk)
            self.wfile.flush()

    def _send_file(self, path: Path, content_type: str, *, gzip: bool) -> None:
        size = path.stat().st_size
        self._headers(HTTPStatus.OK, content_type, size)
        if gzip:
            self.send_header("Content-Encoding", "gzip")
        self.end_headers()
        with path.open("rb") as f:
            while chunk := f.read(1 << 20):
                self.wfile.write(chunk)


class PageServer:
    """r2d2-viz's page for the recording ``feed`` (what the page's viewer reads at ``recording.rrd``; None: the
    viewer opens nothing), served on ``bind:port`` in a thread of its own.

    ``config`` goes into the page as JSON (fixed frame, tool topics); ``on_event`` handles each tool event
    (:data:`EventHandler`; :meth:`set_handler` replaces it). ``port`` 0 picks a free port.
    """

    def __init__(
        self,
        feed: RecordingFeed | None,
        bind: str = "127.0.0.1",
        port: int = 0,
        *,
        config: dict[str, Any] | None = None,
        on_event: EventHandler | None = None,
        token: str | None = None,
        cache: Path | None = None,
    ) -> None:
        self.static = viewer_static()
        self.widget = hooked_widget(widget_js(self.static))  # the viewer followed, and on globalThis for the eye
        self.token = token or secrets.token_urlsafe(24)
        self.feed = feed
        self.config: dict[str, Any] = dict(config or {})
        self._handler = on_event
        self.limit = RateLimit(EVENTS_PER_S, EVENT_BURST)
        self.eyes = EyeReader()
        self.hosts = allowed_hosts(bind)
        self._cache = cache
        self._wasm: tuple[Path, bool] | None = None
        self._wasm_lock = threading.Lock()
        family = socket.AF_INET6 if ":" in bind else socket.AF_INET
        try:
            self._http = _Server((bind, port), family, _Handler)
        except OSError as exc:
            raise ListenError(
                f"--serve: cannot listen on {bind}:{port} for the web page: {exc.strerror}", port
            ) from None
        self._http.page = self
        self.port = int(self._http.server_address[1])
        self.bind = bind
        self._thread = threading.Thread(target=self._http.serve_forever, name="r2d2-viz-page", daemon=True)
        self._thread.start()
        threading.Thread(target=self.wasm, name="r2d2-viz-wasm-gzip", daemon=True).start()

    def url(self, host: str | None = None) -> str:
        """The page's address (with its token): what the user opens. ``localhost`` for 127.0.0.1 and every address
        (what a browser on this machine reaches them by); otherwise the address bound, ``[::1]`` included (``localhost``
        may resolve to 127.0.0.1 only, where nothing listens then)."""
        name = host or ("localhost" if self.bind in ("127.0.0.1", "0.0.0.0", "::") else self.bind)
        name = f"[{name}]" if ":" in name else name
        return f"http://{name}:{self.port}/{self.token}/"

    def set_handler(self, on_event: EventHandler | None) -> None:
        self._handler = on_event

    def handle(self, event: dict[str, Any]) -> str:
        handler = self._handler
        if handler is None:
            raise SinkError("this page takes no tool events")
        return handler(event)

    def html(self) -> bytes:
        """page.html with its configuration (the recording's address, the tools' topics) as JSON in which no
        ``<``, ``>`` or ``&`` is left (a frame named ``<!--<script>`` would swallow the page's script)."""
        config = {"recording": RECORDING if self.feed is not None else None, **self.config}
        text = json.dumps(config).replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")
        return (HERE / "page.html").read_text().replace("__CONFIG__", text).encode()

    def wasm(self) -> tuple[Path, bool]:
        """The wasm to send and whether it is gzip-compressed: compressed on first use (a second caller waits for
        the first), or rerun-notebook's own file if the cache cannot be written (said once, in one line)."""
        with self._wasm_lock:
            if self._wasm is None:
                try:
                    self._wasm = (compressed_wasm(self.static, self._cache), True)
                except OSError as exc:
                    where = self._cache or cache_dir()
                    warn(f"--serve: cannot keep the compressed viewer in {where} ({one_line(exc)}); sent uncompressed")
                    self._wasm = (self.static / WASM, False)
            return self._wasm

    def close(self) -> None:
        self._http.shutdown()
        self._http.server_close()
        self._thread.join(timeout=5)
        self.eyes.close()
