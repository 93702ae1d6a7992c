"""The page's server on loopback: every path needs the run's token; the event endpoint takes only bounded tool
events, at a bounded rate; the wasm goes out gzip-compressed and inflates to rerun-notebook's own file."""

from __future__ import annotations

import gzip
import http.client
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from r2d2_viz.errors import ToolEventError
from r2d2_viz.viewer.web.assets import FOLLOW_PATCH, HERE, viewer_static
from r2d2_viz.viewer.web.events import parse_event
from r2d2_viz.viewer.web.eye import hooked_widget
from r2d2_viz.viewer.web.feed import RecordingFeed
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
    server: PageServer, method: str, path: str, body: bytes | None = None, headers: dict[str, str] | None = None
) -> tuple[int, dict[str, str], bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=60)
    try:
        sent = {"Content-Type": "application/json"} if body else {}
        conn.request(method, path, body=body, headers={**sent, **(headers or {})})
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
    original = (viewer_static() / "widget.js").read_bytes()
    assert status == 200 and js == hooked_widget(original.replace(*(t.encode() for t in FOLLOW_PATCH)))
    assert js.count(b"globalThis.r2d2Viewer = this.viewer;") == 1  # the viewer, for the pose tools' eye
    assert js.count(FOLLOW_PATCH[1].encode()) == 1  # and taught to follow the recording as it grows
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


def test_events_from_a_foreign_host_or_origin_are_refused(page: tuple[PageServer, list[dict[str, Any]]]) -> None:
    """A real POST with the token, as a DNS-rebinding page (its own name in ``Host``) or another site's script
    (its ``Origin``) would send it: refused, nothing handled."""
    server, got = page
    event = json.dumps({"tool": "Publish Point", "points": [[1, 2, 0]]}).encode()
    url = f"/{server.token}/event"
    own = f"localhost:{server.port}"
    assert _request(server, "POST", url, event, {"Host": f"rebind.example:{server.port}"})[0] == 403
    assert _request(server, "POST", url, event, {"Host": own, "Origin": "http://evil.example"})[0] == 403
    assert _request(server, "GET", f"/{server.token}/", headers={"Host": "rebind.example"})[0] == 403
    assert got == []
    assert _request(server, "POST", url, event, {"Host": own, "Origin": f"http://{own}"})[0] == 200
    assert len(got) == 1


def test_a_malformed_event_is_a_4xx_and_nothing_else(capfd: pytest.CaptureFixture[str]) -> None:
    """The review's bodies: a 400-digit coordinate, 4 kB of nested '[' (and a few more), through the real
    parser: each a 4xx, nothing on the operator's terminal."""
    server = PageServer(None, on_event=lambda event: repr(parse_event(event)))
    try:
        url = f"/{server.token}/event"
        bodies = [
            b'{"tool": "Publish Point", "points": [[' + b"9" * 400 + b", 0, 0]]}",
            b"[" * 4000,
            b'{"tool": "Teleop", "linear": ' + b"1" * 400 + b', "angular": 0}',
            b'{"tool": "Publish Point", "points": [[1e999, 0, 0]]}',
            b'{"tool": "Publish Point", "points": [[NaN, 0, 0]]}',
            b"\xff\xfe{}",
            b'{"tool": ["Publish Point"]}',
        ]
        for body in bodies:
            status, _, answer = _request(server, "POST", url, body)
            assert 400 <= status < 500, (body[:60], status, answer)
        assert _request(server, "POST", url, b'{"tool": "Publish Point", "points": [[1, 2, 0]]}')[0] == 200
    finally:
        server.close()
    out, err = capfd.readouterr()
    assert "Traceback" not in err + out and err == ""


def test_bag_strings_in_the_page_config_cannot_end_or_open_a_script() -> None:
    """A TF root named ``<!--<script>`` (or ``</script>``): the config keeps no '<', '>' or '&' (in a script
    element, ``<!--`` then ``<script>`` swallows the rest of the page) and reads back as it was."""
    hostile = "<!--<script></script>&amp;"
    server = PageServer(None, config={"fixed_frame": hostile})
    try:
        _, _, body = _request(server, "GET", f"/{server.token}/")
    finally:
        server.close()
    text = body.decode()
    inside = text.split('type="application/json">')[1].split("</script>")[0]
    assert not set(inside) & set("<>&") and json.loads(inside)["fixed_frame"] == hostile
    scripts = (HERE / "page.html").read_text().count("<script")  # the config's and the page's modules
    assert text.count("<script") == scripts and 'id="toolbar"' in text  # nothing more


def test_the_recording_needs_the_token_and_grows(tmp_path: Path) -> None:
    chunks = [b"RRF2-first"]
    feed = RecordingFeed(lambda: chunks.pop(0) if chunks else None, period=0.01)
    server = PageServer(feed)
    try:
        assert _request(server, "GET", "/recording.rrd")[0] == 404
        assert _request(server, "GET", f"/{server.token[:-1]}x/recording.rrd")[0] == 404
        conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=30)
        conn.request("GET", f"/{server.token}/recording.rrd")
        response = conn.getresponse()
        assert response.status == 200 and response.read(10) == b"RRF2-first"
        chunks.append(b"-then-more")
        assert response.read(10) == b"-then-more"  # the same response, as it grows
        feed.close()
        assert response.read() == b""  # closed with the feed
        conn.close()
    finally:
        server.close()


def test_an_unwritable_cache_still_serves_the_viewer(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    """The cache folder cannot be made (under a file here: the tests run as root, who writes any read-only
    folder): the wasm goes out uncompressed, one warning line says why, no traceback."""
    blocker = tmp_path / "cache"
    blocker.write_text("a file where the cache folder would be")
    server = PageServer(None, cache=blocker / "r2d2-viz" / "web")
    try:
        status, headers, body = _request(server, "GET", f"/{server.token}/re_viewer_bg.wasm")
    finally:
        server.close()
    assert status == 200 and "Content-Encoding" not in headers
    assert body == (viewer_static() / "re_viewer_bg.wasm").read_bytes()
    err = capfd.readouterr().err
    assert err.count("\n") == 1 and "cannot keep the compressed viewer" in err and "Traceback" not in err


def test_the_url_printed_for_bind_ipv6_loopback_is_where_the_server_listens(tmp_path: Path) -> None:
    """Issue 44, item 16: with ``--bind ::1`` the app printed ``http://localhost:PORT/…``, and ``localhost`` may
    name 127.0.0.1 only (it does here: /etc/hosts), where nothing listens. The installed CLI now prints
    ``http://[::1]:PORT/…``, and the page is there."""
    import re
    import signal
    import socket
    import subprocess
    import sys
    import time

    with socket.socket(socket.AF_INET6) as s:
        s.bind(("::1", 0))
        port = int(s.getsockname()[1])
    err = tmp_path / "stderr"
    exe = Path(sys.executable).parent / "r2d2-viz"
    with err.open("wb") as e:
        app = subprocess.Popen(
            [str(exe), "--serve", "--bind", "::1", "--web-port", str(port)],
            stdout=subprocess.DEVNULL, stderr=e, stdin=subprocess.DEVNULL, start_new_session=True,
        )  # fmt: skip
    try:
        deadline = time.monotonic() + 90
        while not (found := re.search(r"serving: open (\S+) in a browser", err.read_text(errors="replace"))):
            assert app.poll() is None and time.monotonic() < deadline, err.read_text(errors="replace")
            time.sleep(0.1)
        url = found.group(1)
        assert re.fullmatch(rf"http://\[::1\]:{port}/[A-Za-z0-9_-]+/", url), url
        conn = http.client.HTTPConnection("::1", port, timeout=60)
        try:
            conn.request("GET", url.split(f":{port}", 1)[1], headers={"Host": f"[::1]:{port}"})
            assert conn.getresponse().status == 200
        finally:
            conn.close()
    finally:
        if app.poll() is None:
            app.send_signal(signal.SIGINT)
        assert app.wait(timeout=30) == 0
