"""The token's guard in front of ``--dataset --serve``'s two servers, with two plain HTTP servers of the tests
standing for Rerun's catalog and web viewer: nothing reaches them without the token's cookie (the printed address
gives it), gRPC-web calls go to the catalog, the rest to the viewer, the ``Host`` must name this server, and a
stream whose client left ends (Rerun's catalog waits for its streams when it stops)."""

from __future__ import annotations

import http.client
import socket
import threading
import time
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from r2d2_viz.viewer.web.guard import DatasetGuard


class _Upstream(BaseHTTPRequestHandler):
    """Answers with its own name, the path and the headers it got; ``/stream`` sends a line, then nothing."""

    protocol_version = "HTTP/1.1"

    def log_message(self, format: str, *args: object) -> None:
        return

    def _answer(self) -> None:
        length = int(self.headers.get("Content-Length", "0"))
        got = self.rfile.read(length)
        if self.path == "/stream":
            self.send_response(200)
            self.send_header("Transfer-Encoding", "chunked")
            self.end_headers()
            self.wfile.write(b"6\r\nstart\n\r\n")
            self.server.streaming.set()  # type: ignore[attr-defined]
            self.server.ended.wait(30)  # type: ignore[attr-defined]
            return
        name = self.server.name  # type: ignore[attr-defined]
        body = f"{name} {self.command} {self.path} {dict(self.headers)!r} {got!r}".encode()
        self.send_response(200)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    do_GET = do_POST = _answer


@pytest.fixture
def guard() -> Iterator[tuple[DatasetGuard, ThreadingHTTPServer]]:
    servers = []
    for name in ("catalog", "viewer"):
        server = ThreadingHTTPServer(("127.0.0.1", 0), _Upstream)
        server.daemon_threads = True
        server.name, server.streaming, server.ended = name, threading.Event(), threading.Event()  # type: ignore[attr-defined]
        threading.Thread(target=server.serve_forever, daemon=True).start()
        servers.append(server)
    addresses = [("127.0.0.1", int(s.server_address[1])) for s in servers]
    door = DatasetGuard(addresses[0], addresses[1], "127.0.0.1", 0, token="t0ken")
    try:
        yield door, servers[0]
    finally:
        door.close()
        for server in servers:
            server.ended.set()  # type: ignore[attr-defined]
            server.shutdown()
            server.server_close()


def _ask(port: int, method: str, path: str, headers: dict[str, str], body: bytes | None = None
         ) -> tuple[int, dict[str, str], bytes]:  # fmt: skip
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    try:
        conn.request(method, path, body=body, headers=headers)
        response = conn.getresponse()
        return response.status, dict(response.getheaders()), response.read()
    finally:
        conn.close()


def test_nothing_is_forwarded_without_the_token(guard: tuple[DatasetGuard, ThreadingHTTPServer]) -> None:
    door, _ = guard
    assert door.url() == f"http://localhost:{door.port}/t0ken/"
    grpc = {"Content-Type": "application/grpc-web+proto"}
    refused = [("/", {}), ("/x", {"Cookie": "r2d2_viz_dataset=t0kex"}), ("/t0kenx/", {}),
               ("/f", {**grpc, "Cookie": "other=t0ken"}), ("/f", {**grpc, "Cookie": "\x7f;;="})]  # fmt: skip
    for path, headers in refused:
        status, _, body = _ask(door.port, "POST" if "Content-Type" in headers else "GET", path, headers, b"q")
        assert status == 403 and b"catalog" not in body and b"viewer" not in body, (path, body)
    status, _, body = _ask(door.port, "GET", "/", {"Host": "rebind.example", "Cookie": "r2d2_viz_dataset=t0ken"})
    assert status == 403 and b"not a name of this server" in body  # DNS rebinding


def test_the_printed_address_gives_the_cookie_and_the_viewer(guard: tuple[DatasetGuard, ThreadingHTTPServer]) -> None:
    door, _ = guard
    status, headers, _ = _ask(door.port, "GET", "/t0ken/", {"Host": f"127.0.0.1:{door.port}"})
    assert status == 303 and headers["Location"] == f"/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{door.port}"
    assert headers["Set-Cookie"] == "r2d2_viz_dataset=t0ken; Path=/; HttpOnly; SameSite=Strict"
    cookie = {"Cookie": "a=b; r2d2_viz_dataset=t0ken"}
    status, _, body = _ask(door.port, "GET", "/index.html?url=x", cookie)
    assert status == 200 and body.startswith(b"viewer GET /index.html?url=x ")
    assert b"t0ken" not in body and "'Connection': 'close'" in body.decode()  # the cookie stays here
    chunked = {**cookie, "Transfer-Encoding": "chunked"}
    status, _, body = _ask(door.port, "POST", "/x", chunked, b"")
    assert status == 411 and b"viewer" not in body  # only bodies of known length are relayed (no smuggling)
    grpc = {**cookie, "Content-Type": "application/grpc-web+proto"}
    status, _, body = _ask(door.port, "POST", "/rerun.cloud.v1alpha1.RerunCloudService/FindEntries", grpc, b"\0" * 5)
    assert (
        status == 200
        and body.startswith(b"catalog POST /rerun.cloud")
        and body.endswith(b"'\\x00\\x00\\x00\\x00\\x00'")
    )


def test_a_stream_whose_client_left_ends(guard: tuple[DatasetGuard, ThreadingHTTPServer]) -> None:
    door, catalog = guard
    client = socket.create_connection(("127.0.0.1", door.port), timeout=10)
    client.sendall(b"GET /stream HTTP/1.1\r\nHost: localhost\r\nCookie: r2d2_viz_dataset=t0ken\r\n"
                   b"Content-Type: application/grpc-web\r\n\r\n")  # fmt: skip
    got = b""
    while b"start" not in got:  # (the head and the first chunk may come apart)
        more = client.recv(1024)
        assert more, got
        got += more
    assert catalog.streaming.wait(10)  # type: ignore[attr-defined]
    assert len(door._relays) == 1
    client.close()
    deadline = time.monotonic() + 10
    while door._relays and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not door._relays  # the relay ended, the catalog's connection closed, though the stream said nothing


def test_a_server_behind_that_does_not_listen_is_a_502() -> None:
    """The CI run of issue 44 saw the door drop a request unanswered while Rerun's web viewer was not yet listening
    (``RemoteDisconnected``): a server behind that refuses the connection is now an answer, 502."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        gone = ("127.0.0.1", int(s.getsockname()[1]))  # bound, not listening: connections refused
        door = DatasetGuard(gone, gone, "127.0.0.1", 0, token="t0ken")
        try:
            status, _, body = _ask(door.port, "GET", "/", {"Cookie": "r2d2_viz_dataset=t0ken"})
        finally:
            door.close()
    assert status == 502 and b"does not answer" in body
