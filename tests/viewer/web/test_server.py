"""The page's server on loopback: every path needs the run's token; the event endpoint takes only bounded tool
events, at a bounded rate; the wasm goes out gzip-compressed and inflates to rerun-notebook's own file."""

from __future__ import annotations

import gzip
import http.client
import json
from collections.abc import Iterator
from typing import Any

import pytest

from r2d2_viz.errors import ToolEventError
from r2d2_viz.viewer.web.assets import viewer_static
from r2d2_viz.viewer.web.server import MAX_EVENT_BYTES, PageServer, RateLimit


@pytest.fixture
def page() -> Iterator[tuple[PageServer, list[dict[str, Any]]]]:
    got: list[dict[str, Any]] = []

    def handle(event: dict[str, Any]) -> str:
        if event.get("tool") != "Publish Point":
            raise ToolEventError("unknown tool")
        got.append(event)
        return "clicked"

    server = PageServer(None, "127.0.0.1", 0, config={"fixed_frame": "map"}, on_event=handle)
    try:
        yield server, got
    finally:
        server.close()


def _request(
    server: PageServer, method: str, path: str, body: bytes | None = None
) -> tuple[int, dict[str, str], bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=60)
    try:
        conn.request(method, path, body=body, headers={"Content-Type": "application/json"} if body else {})
        response = conn.getresponse()
        return response.status, dict(response.getheaders()), response.read()
    finally:
        conn.close()


def test_the_page_and_the_viewer_need_the_token(page: tuple[PageServer, list[dict[str, Any]]]) -> None:
    server, _ = page
    assert server.url().startswith("http://localhost:") and server.url().endswith(f"/{server.token}/")
    status, headers, body = _request(server, "GET", f"/{server.token}/")
    assert status == 200 and headers["Content-Type"].startswith("text/html")
    config = json.loads(body.decode().split('type="application/json">')[1].split("</script>")[0])
    assert config == {"recording": None, "fixed_frame": "map"}
    for name in ("2D Pose Estimate", "2D Goal Pose", "Publish Point", "Measure", "Teleop"):  # RViz's names
        assert f">{name}<" in body.decode()
    status, _, js = _request(server, "GET", f"/{server.token}/widget.js")
    assert status == 200 and js == (viewer_static() / "widget.js").read_bytes()
    for path in ("/", "/widget.js", "/re_viewer_bg.wasm", f"/{server.token[:-1]}x/", f"/{server.token}/../x"):
        assert _request(server, "GET", path)[0] == 404, path


def test_the_wasm_is_sent_compressed(page: tuple[PageServer, list[dict[str, Any]]]) -> None:
    server, _ = page
    status, headers, body = _request(server, "GET", f"/{server.token}/re_viewer_bg.wasm")
    wasm = (viewer_static() / "re_viewer_bg.wasm").read_bytes()
    assert status == 200 and headers["Content-Encoding"] == "gzip" and headers["Content-Type"] == "application/wasm"
    assert len(body) < len(wasm) / 3 and gzip.decompress(body) == wasm


def test_events_need_the_token_and_are_bounded(page: tuple[PageServer, list[dict[str, Any]]]) -> None:
    server, got = page
    event = json.dumps({"tool": "Publish Point", "points": [[1, 2, 0]]}).encode()
    assert _request(server, "POST", "/event", event)[0] == 404  # no token: nothing handled
    assert _request(server, "POST", "/wrong-token/event", event)[0] == 404
    assert got == []
    status, _, body = _request(server, "POST", f"/{server.token}/event", event)
    assert status == 200 and json.loads(body) == {"line": "clicked"} and len(got) == 1
    status, _, body = _request(server, "POST", f"/{server.token}/event", b'{"tool": "Select"}')
    assert status == 400 and json.loads(body) == {"error": "unknown tool"}
    assert _request(server, "POST", f"/{server.token}/event", b"[1, 2]")[0] == 400
    assert _request(server, "POST", f"/{server.token}/event", b"{" * 10)[0] == 400
    assert _request(server, "POST", f"/{server.token}/event", b" " * (MAX_EVENT_BYTES + 1))[0] == 413
    assert len(got) == 1


def test_the_rate_is_bounded() -> None:
    now = [0.0]
    limit = RateLimit(10.0, 3, clock=lambda: now[0])
    assert [limit.take() for _ in range(5)] == [True, True, True, False, False]  # the burst, then nothing
    now[0] = 0.1  # one event's worth of time later
    assert [limit.take() for _ in range(2)] == [True, False]
    now[0] = 100.0  # a long pause refills to the burst, no more
    assert sum(limit.take() for _ in range(10)) == 3
