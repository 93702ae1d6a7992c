"""Who gets in to the page's server: a threaded HTTP server that no idle or slow client can fill, and the names
a request's ``Host`` and ``Origin`` may carry. Pure: no rerun.

A connection *waits* until its request has shown the token (each request of a kept-alive connection waits again).
At most :data:`MAX_WAITING` wait at once: a newer connection takes the place of the oldest waiting one of the
client that has the most waiting (whoever holds idle connections loses its own first), and every read times out
after :data:`READ_TIMEOUT_S`. Requests that showed the token are *served*, at most :data:`MAX_SERVING` at once.
"""

from __future__ import annotations

import ipaddress
import os
import select
import socket
import threading
from collections import Counter
from http.server import ThreadingHTTPServer
from typing import Any

from r2d2_viz.errors import DEBUG_ENV

MAX_WAITING = 32
MAX_SERVING = 16
"""Requests with the token at once: the page, its files, the recording each open page follows, the events."""
MAX_THREADS = MAX_WAITING + MAX_SERVING
READ_TIMEOUT_S = 10.0
"""A read (a request's line, headers or body) or a write that takes longer ends the connection."""
KEEP_ALIVE_S = 330.0
"""How long a connection that showed the token may wait for its next request: longer than a browser keeps an idle
connection (Chromium: 300 s), so that the browser, not the server, closes it (a POST sent on a connection the
server has just closed fails in the page: "Failed to fetch")."""
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")
WILDCARDS = ("0.0.0.0", "::", "")


def allowed_hosts(bind: str) -> frozenset[str]:
    """The host names a request may name in ``Host`` (lower case, without port) besides IP addresses: the loopback
    names, the ``--bind`` name, and this machine's names when bound to every address."""
    names = {*LOOPBACK_NAMES, bind.lower()}
    if bind in WILDCARDS:
        names |= {socket.gethostname().lower(), socket.getfqdn().lower()}
    return frozenset(names)


def host_name(host_header: str) -> str:
    """``Host``'s name, without its port and brackets, lower case (``[::1]:9090`` → ``::1``)."""
    host = host_header.strip().lower()
    if host.startswith("["):
        return host[1:].split("]", 1)[0]
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host


def host_allowed(host_header: str | None, names: frozenset[str]) -> bool:
    """Whether ``Host`` names this server: a bound name or an IP address (what DNS rebinding cannot send)."""
    if not host_header:
        return False
    name = host_name(host_header)
    if name in names or name.endswith(".localhost"):
        return True
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


def origin_allowed(origin: str | None, host_header: str | None) -> bool:
    """A POST's ``Origin``: none (not a browser) or this very page's (``http://`` and the same ``Host``)."""
    return origin is None or (host_header is not None and origin.lower() == f"http://{host_header.lower()}")


def peer_gone(connection: socket.socket) -> bool:
    """Whether the other end of ``connection`` has closed it (or it broke), without waiting or taking any byte: a
    follower of the recording sends nothing after its request, so a readable socket with nothing to read is its
    end."""
    try:
        if not select.select([connection], [], [], 0)[0]:
            return False
        return connection.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b""
    except BlockingIOError:
        return False
    except (OSError, ValueError):  # reset, or already closed here
        return True


KEEPALIVE_PROBES = ((socket.SOL_SOCKET, "SO_KEEPALIVE", 1), (socket.IPPROTO_TCP, "TCP_KEEPIDLE", 30),
                    (socket.IPPROTO_TCP, "TCP_KEEPINTVL", 10), (socket.IPPROTO_TCP, "TCP_KEEPCNT", 3))  # fmt: skip
"""A long-lived connection whose peer vanished without closing it (a machine asleep, a cable out) breaks after about
a minute of unanswered TCP keep-alive probes; :func:`peer_gone` then sees it (where the options exist: Linux)."""


def probe_peer(connection: socket.socket) -> None:
    """TCP keep-alive probes on ``connection`` (:data:`KEEPALIVE_PROBES`)."""
    for level, name, value in KEEPALIVE_PROBES:
        if hasattr(socket, name):
            try:
                connection.setsockopt(level, getattr(socket, name), value)
            except OSError:
                pass


class DoorServer(ThreadingHTTPServer):
    """The bounded server (see the module's docstring); handlers call :meth:`waiting`, :meth:`admit` and
    :meth:`done` around each request."""

    daemon_threads = True
    request_queue_size = 128  # the listen backlog (socketserver's 5 makes a burst of connects wait seconds)

    def __init__(self, address: tuple[str, int], family: socket.AddressFamily, handler: Any) -> None:
        self.address_family = family
        self._lock = threading.Lock()
        self._slots = threading.BoundedSemaphore(MAX_THREADS)
        self._waiting: dict[socket.socket, str] = {}  # in the order they started waiting
        self._serving = threading.BoundedSemaphore(MAX_SERVING)
        super().__init__(address, handler)

    def process_request(self, request: Any, client_address: Any) -> None:
        if not self._slots.acquire(blocking=False):  # every thread busy serving: a flood is dropped, not queued
            self.shutdown_request(request)
            return
        self.waiting(request, str(client_address[0]))
        super().process_request(request, client_address)

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            with self._lock:
                self._waiting.pop(request, None)
            self._slots.release()

    def handle_error(self, request: Any, client_address: Any) -> None:
        if os.environ.get(DEBUG_ENV):  # otherwise a client gone, a read timed out: nothing for the operator
            super().handle_error(request, client_address)

    def waiting(self, connection: socket.socket, client: str | None = None) -> None:
        """``connection`` waits for a request; the oldest waiting one of the busiest client goes if too many do."""
        victim: socket.socket | None = None
        with self._lock:
            if client is None:
                client = self._client(connection)
            self._waiting[connection] = client
            if len(self._waiting) > MAX_WAITING:
                busiest = Counter(self._waiting.values()).most_common(1)[0][0]
                victim = next(c for c, who in self._waiting.items() if who == busiest)
                del self._waiting[victim]
        if victim is not None:
            try:
                victim.shutdown(socket.SHUT_RDWR)  # its thread's read returns; the thread ends
            except OSError:
                pass

    @staticmethod
    def _client(connection: socket.socket) -> str:
        try:
            return str(connection.getpeername()[0])
        except OSError:
            return ""

    def admit(self, connection: socket.socket) -> bool:
        """The request on ``connection`` showed the token: served, if fewer than :data:`MAX_SERVING` are."""
        with self._lock:
            self._waiting.pop(connection, None)
        return self._serving.acquire(blocking=False)

    def done(self) -> None:
        """An admitted request has been answered."""
        self._serving.release()
