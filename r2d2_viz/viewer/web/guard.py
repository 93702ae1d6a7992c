"""``--dataset --serve``'s one door: Rerun's catalog server and its web viewer behind the run's token. Neither of
Rerun's servers takes a token, so both listen on loopback ports of their own, and the browser reaches them only
through this proxy, on the port the user serves on. Pure: no rerun.

The address the app prints is ``http://HOST:PORT/<token>/``: that request is answered here, with a cookie holding
the token (``HttpOnly``, ``SameSite=Strict``, as Jupyter keeps its token once shown) and a redirect to the viewer
opened on the catalog at this same address (``/?url=rerun+http://HOST:PORT``). Every other request must carry that
cookie — the viewer's files, then its gRPC-web calls to the catalog, which Rerun's web viewer sends to the
catalog's origin (this one: same-origin fetches carry the cookie) — or it is refused (403) and nothing is
forwarded. gRPC-web calls (``Content-Type: application/grpc…``) go to the catalog, the rest to the web viewer; one
request per connection, relayed as it comes (the catalog's answers are streams). The limits are the page's
(:mod:`.door`): ``Host`` a bound name or an IP address, a connection that has not shown the token closed after
:data:`~.door.READ_TIMEOUT_S`, at most :data:`~.door.MAX_SERVING` relayed at once.
"""

from __future__ import annotations

import secrets
import select
import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from http import HTTPStatus
from http.cookies import CookieError, SimpleCookie
from http.server import BaseHTTPRequestHandler
from typing import Any
from urllib.parse import quote

from r2d2_viz.errors import ListenError
from r2d2_viz.viewer.web.door import READ_TIMEOUT_S, DoorServer, allowed_hosts, host_allowed, peer_gone, probe_peer

COOKIE = "r2d2_viz_dataset"
MAX_BODY_BYTES = 16 << 20
"""A gRPC-web request's body (the viewer's queries are small; the catalog's answers are not bounded here)."""
UPSTREAM_TIMEOUT_S = 600.0
"""How long a relayed answer may stay silent (a query the catalog works on)."""
HOP_HEADERS = frozenset({"connection", "keep-alive", "proxy-connection", "proxy-authorization", "te", "upgrade",
                         "cookie", "host"})  # fmt: skip
"""Not forwarded: the hop's own, and the cookie holding the token (Rerun's servers need neither)."""

Address = tuple[str, int]


class _Server(DoorServer):
    guard: DatasetGuard


class _Handler(BaseHTTPRequestHandler):
    server: _Server
    protocol_version = "HTTP/1.1"
    timeout = READ_TIMEOUT_S

    def log_message(self, format: str, *args: Any) -> None:  # quiet: the app prints its own lines
        return

    def handle_one_request(self) -> None:
        self._admitted = False
        try:
            super().handle_one_request()
        finally:
            if self._admitted:
                self.server.done()

    def __getattr__(self, name: str) -> Any:
        if name.startswith("do_"):  # every method is relayed alike (GET, POST, OPTIONS, …)
            return self._relay
        raise AttributeError(name)

    def _relay(self) -> None:
        self.close_connection = True
        guard = self.server.guard
        if not host_allowed(self.headers.get("Host"), guard.hosts):
            self._answer(HTTPStatus.FORBIDDEN, "not a name of this server: open the address the app printed")
            return
        prefix = f"/{guard.token}"
        path = self.path.split("?", 1)[0]
        if self.command == "GET" and secrets.compare_digest(path.rstrip("/").encode(), prefix.encode()):
            self._enter()
            return
        if not self._has_token():
            self._answer(HTTPStatus.FORBIDDEN, "no token: open the address the app printed (it ends in the token)")
            return
        self._admitted = self.server.admit(self.connection)
        if not self._admitted:
            self._answer(HTTPStatus.SERVICE_UNAVAILABLE, "busy")
            return
        grpc = self.headers.get("Content-Type", "").lower().startswith("application/grpc")
        self._forward(guard.catalog if grpc else guard.viewer)

    def _has_token(self) -> bool:
        try:
            morsel = SimpleCookie(self.headers.get("Cookie", "")).get(COOKIE)
        except CookieError:
            return False
        token = self.server.guard.token
        return morsel is not None and secrets.compare_digest(morsel.value.encode(), token.encode())

    def _enter(self) -> None:
        """The printed address: the cookie, and the viewer opened on the catalog at the address the browser used."""
        host = str(self.headers.get("Host"))
        self.send_response(HTTPStatus.SEE_OTHER)
        self.send_header("Location", f"/?url={quote(f'rerun+http://{host}', safe='')}")
        self.send_header("Set-Cookie", f"{COOKIE}={self.server.guard.token}; Path=/; HttpOnly; SameSite=Strict")
        self.send_header("Content-Length", "0")
        self.send_header("Cache-Control", "no-store")
        self.send_header("Referrer-Policy", "no-referrer")
        self.end_headers()

    def _answer(self, status: HTTPStatus, why: str) -> None:
        body = f"{why}\n".encode()
        self.send_response(status)
        self.send_header("Content-Type", "text/plain")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def _forward(self, upstream: Address) -> None:
        try:
            length = int(self.headers.get("Content-Length", "0"))
        except ValueError:
            length = -1
        if self.headers.get("Transfer-Encoding") is not None or not 0 <= length <= MAX_BODY_BYTES:
            self._answer(HTTPStatus.LENGTH_REQUIRED, "a body of known length, at most 16 MiB")
            return
        body = self.rfile.read(length)
        head = [f"{self.command} {self.path} HTTP/1.1", f"Host: {upstream[0]}:{upstream[1]}", "Connection: close"]
        head += [f"{k}: {v}" for k, v in self.headers.items() if k.lower() not in HOP_HEADERS and v.isprintable()]
        guard = self.server.guard
        try:
            up = socket.create_connection(upstream, timeout=UPSTREAM_TIMEOUT_S)
        except OSError:  # the server behind is not there (stopped, or not yet listening): say so
            self._answer(HTTPStatus.BAD_GATEWAY, "the server behind this door does not answer")
            return
        try:
            with up, guard.relaying(up):
                up.sendall(("\r\n".join(head) + "\r\n\r\n").encode("latin-1") + body)
                self._pipe(up)
        except OSError:  # the server behind, or the client, went: the connection ends
            return

    def _pipe(self, up: socket.socket) -> None:
        """The answer from ``up`` to the client as it comes, until either ends (a client gone from a silent stream
        is seen at once, not when the stream next sends: Rerun's catalog waits for its streams when it stops)."""
        client = self.connection
        probe_peer(client)  # (one that vanished without closing: seen in about a minute)
        while True:
            readable = select.select([up, client], [], [], UPSTREAM_TIMEOUT_S)[0]
            if not readable:
                return
            if client in readable and (peer_gone(client) or not client.recv(1 << 16)):
                return  # (bytes after the request: none are expected; dropped)
            if up in readable:
                data = up.recv(1 << 16)
                if not data:
                    return
                self.wfile.write(data)  # (the client's writes time out after READ_TIMEOUT_S)


class DatasetGuard:
    """The proxy on ``bind:port`` (0: a free one) in front of Rerun's ``catalog`` and web ``viewer`` (their
    loopback addresses), in a thread of its own; ``token``: the run's secret."""

    def __init__(self, catalog: Address, viewer: Address, bind: str, port: int, token: str | None = None) -> None:
        self.catalog, self.viewer = catalog, viewer
        self.token = token or secrets.token_urlsafe(24)
        self.hosts = allowed_hosts(bind)
        family = socket.AF_INET6 if ":" in bind else socket.AF_INET
        try:
            self._http = _Server((bind, port), family, _Handler)
        except OSError as exc:
            why = f"--serve: cannot listen on {bind}:{port} for the web viewer: {exc.strerror}"
            raise ListenError(why, port) from None
        self._http.guard = self
        self._relays: set[socket.socket] = set()
        self._lock = threading.Lock()
        self.bind = bind
        self.port = int(self._http.server_address[1])
        self._thread = threading.Thread(target=self._http.serve_forever, name="r2d2-viz-guard", daemon=True)
        self._thread.start()

    def url(self) -> str:
        """The address to open (with the token), by the name the server listens on (``localhost`` for 127.0.0.1
        and every address; ``[::1]`` for ::1)."""
        name = "localhost" if self.bind in ("127.0.0.1", "0.0.0.0", "::") else self.bind
        name = f"[{name}]" if ":" in name else name
        return f"http://{name}:{self.port}/{self.token}/"

    @contextmanager
    def relaying(self, upstream: socket.socket) -> Iterator[None]:
        """``upstream`` is open to one of Rerun's servers while the block runs (:meth:`close` ends it)."""
        with self._lock:
            self._relays.add(upstream)
        try:
            yield
        finally:
            with self._lock:
                self._relays.discard(upstream)

    def close(self) -> None:
        """No new connections; every relay ended (so that Rerun's servers, which wait for them, can stop)."""
        self._http.shutdown()
        self._http.server_close()
        with self._lock:
            for upstream in self._relays:
                try:
                    upstream.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
        self._thread.join(timeout=5)
