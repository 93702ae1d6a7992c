"""Who gets in: idle and slow connections (raw sockets, as the review found them) cannot lock the operator's page
out; ``Host`` must name the server (DNS rebinding) and a POST's ``Origin`` be the page's own."""

from __future__ import annotations

import http.client
import socket
from collections.abc import Iterator

import pytest

from r2d2_viz.viewer.web import door, server
from r2d2_viz.viewer.web.door import allowed_hosts, host_allowed, origin_allowed, peer_gone, probe_peer
from r2d2_viz.viewer.web.server import PageServer


@pytest.fixture
def page() -> Iterator[PageServer]:
    served = PageServer(None, "127.0.0.1", 0)
    try:
        yield served
    finally:
        served.close()


def _operator_gets_the_page(page: PageServer) -> int:
    conn = http.client.HTTPConnection("127.0.0.1", page.port, timeout=30)
    try:
        conn.request("GET", f"/{page.token}/")
        response = conn.getresponse()
        response.read()
        return response.status
    finally:
        conn.close()


@pytest.mark.parametrize("idle", [16, 100])
def test_idle_connections_do_not_lock_the_operator_out(page: PageServer, idle: int) -> None:
    """Connections that send ``GET /`` and wait (no token, no end of headers): the review's 16 took every slot."""
    sockets = []
    try:
        for _ in range(idle):
            s = socket.create_connection(("127.0.0.1", page.port), timeout=30)
            s.sendall(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n")  # and never the blank line
            sockets.append(s)
        assert _operator_gets_the_page(page) == 200
        assert _operator_gets_the_page(page) == 200  # and again: the idle ones did not come back for the place
    finally:
        for s in sockets:
            s.close()


def test_a_connection_that_shows_no_token_is_closed_after_the_read_timeout(
    page: PageServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(server._Handler, "timeout", 0.5)
    with socket.create_connection(("127.0.0.1", page.port), timeout=30) as s:
        s.sendall(b"GET / HT")  # a request line never finished
        assert s.recv(100) == b""  # closed by the server (the client would wait 30 s)


def test_the_names_a_request_may_carry() -> None:
    loopback = allowed_hosts("127.0.0.1")
    for host in ("localhost:9090", "127.0.0.1:9090", "[::1]:9090", "LOCALHOST", "app.localhost:9090", "10.0.0.5"):
        assert host_allowed(host, loopback), host
    for host in ("evil.example:9090", "evil.example", "127.0.0.1.nip.io:9090", "", None):  # DNS rebinding names
        assert not host_allowed(host, loopback), host
    assert host_allowed("robot-lab:9090", allowed_hosts("robot-lab"))
    assert host_allowed(f"{socket.gethostname()}:9090", allowed_hosts("0.0.0.0"))
    assert origin_allowed(None, "localhost:9090")  # not a browser: curl, a script
    assert origin_allowed("http://localhost:9090", "localhost:9090")
    for origin in ("http://evil.example", "null", "http://localhost:9091", "https://localhost:9090"):
        assert not origin_allowed(origin, "localhost:9090"), origin


def test_the_limits_leave_room_for_the_page() -> None:
    """The page's browser holds a few keep-alive connections and one recording stream per tab."""
    assert door.MAX_SERVING >= 8 and door.MAX_WAITING >= 16 and door.READ_TIMEOUT_S <= 30


def test_a_peer_that_closed_is_gone_and_one_that_sent_bytes_is_not() -> None:
    ours, theirs = socket.socketpair()
    with ours:
        assert not peer_gone(ours)  # connected, silent: a follower waiting for bytes
        theirs.sendall(b"x")
        assert not peer_gone(ours) and ours.recv(1) == b"x"  # bytes are not an end (and none was taken)
        theirs.close()
        assert peer_gone(ours)
    assert peer_gone(ours)  # closed here too


def test_a_follower_is_probed_so_that_a_vanished_one_is_seen() -> None:
    """A peer gone without a FIN sends nothing to see: TCP keep-alive probes break the connection after
    30 + 3 x 10 s of silence (Linux's defaults would wait two hours)."""
    with socket.create_server(("127.0.0.1", 0)) as listener:
        with socket.create_connection(listener.getsockname()) as ours, listener.accept()[0]:
            probe_peer(ours)
            assert ours.getsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE) == 1
            if hasattr(socket, "TCP_KEEPIDLE"):
                idle = ours.getsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPIDLE)
                interval = ours.getsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPINTVL)
                count = ours.getsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPCNT)
                assert idle + interval * count == 60
