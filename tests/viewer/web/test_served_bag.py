"""``r2d2-viz --bag BAG --serve`` run as a user runs it (the CLI in a subprocess), on a bag whose TF root is named
to attack the page and the terminal (``<!--<script>`` and escape sequences that rewrite the lines above and the
terminal's title), with a cache folder that cannot be written: one door (the page's port, nothing else listening,
the recording under the token), the page whole, the terminal's lines with their control characters shown, the
viewer served, and the page still up after the bag ended, until Ctrl-C."""

from __future__ import annotations

import http.client
import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

from bagmaker import T0, BagSpec, tf_message, write_bag
from conftest import listening_addresses

from r2d2_viz.viewer.web.assets import HERE, WASM, viewer_static

HOSTILE = "<!--<script>\x1b[2A\x1b[2Kr2d2-viz: all fine\x1b]0;pwned\x07"
"""A frame name: opens an HTML comment and a script, moves the cursor up two lines, erases one, sets the title."""


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _get(port: int, path: str, headers: dict[str, str] | None = None, body: bytes | None = None) -> tuple[int, bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    try:
        conn.request("POST" if body is not None else "GET", path, body=body, headers=headers or {})
        response = conn.getresponse()
        return response.status, response.read()
    finally:
        conn.close()


def _wait_for(path: Path, pattern: str, app: subprocess.Popen[bytes], timeout: float = 60) -> re.Match[str]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if found := re.search(pattern, path.read_text(errors="replace")):
            return found
        assert app.poll() is None, path.read_text(errors="replace")
        time.sleep(0.1)
    raise AssertionError(f"{pattern!r} not in: {path.read_text(errors='replace')}")


def test_a_hostile_bag_served_until_ctrl_c(tmp_path: Path) -> None:
    spec = BagSpec()
    for k in range(20):  # two seconds of a robot moving away from the hostile root
        t = T0 + k * 100_000_000
        spec.add("/tf", t, tf_message([(t, HOSTILE, "base_link", [k * 0.1, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])]))
    bag = write_bag(tmp_path / "hostile", spec)
    blocker = tmp_path / "cache"
    blocker.write_text("a file where the cache folder would be (root writes any read-only folder)")
    grpc_port, web_port = _free_port(), _free_port()
    out, err = tmp_path / "stdout", tmp_path / "stderr"
    exe = Path(sys.executable).parent / "r2d2-viz"
    command = [str(exe), "--bag", str(bag), "--serve", "--port", str(grpc_port), "--web-port", str(web_port)]
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "XDG_CACHE_HOME": str(blocker)}
    with out.open("wb") as o, err.open("wb") as e:
        app = subprocess.Popen(command, stdout=o, stderr=e, stdin=subprocess.DEVNULL, env=env, start_new_session=True)
    try:
        url = _wait_for(err, r"serving: open (\S+) in a browser", app).group(1)
        token = url.rstrip("/").rsplit("/", 1)[1]
        base = f"/{token}/"

        # one door: nothing listens on the gRPC port, no child process; the recording only with the token
        assert listening_addresses(grpc_port) == set()
        assert Path(f"/proc/{app.pid}/task/{app.pid}/children").read_text().strip() == ""
        assert _get(web_port, "/recording.rrd")[0] == 404
        conn = http.client.HTTPConnection("127.0.0.1", web_port, timeout=60)
        conn.request("GET", base + "recording.rrd")
        stream = conn.getresponse()
        assert stream.status == 200 and stream.read1(4) == b"RRF2"  # Rerun's RRD magic
        conn.close()

        # the page whole: the hostile root reaches its config as data, not markup
        status, page = _get(web_port, base)
        config = page.decode().split('type="application/json">')[1].split("</script>")[0]
        assert status == 200 and "<" not in config and json.loads(config)["fixed_frame"] == HOSTILE
        scripts = (HERE / "page.html").read_text().count("<script")  # the config's and the page's modules
        assert page.decode().count("<script") == scripts and 'id="toolbar"' in page.decode()

        # the viewer served although the cache cannot be written
        status, wasm = _get(web_port, base + WASM)
        assert status == 200 and wasm == (viewer_static() / WASM).read_bytes()

        # a click: its line names the frame on stdout with the escapes shown, never sent; foreign Host/Origin refused
        event = json.dumps({"tool": "Publish Point", "points": [[1.0, 2.0, 0.0]]}).encode()
        own = f"localhost:{web_port}"
        assert (
            _get(web_port, base + "event", {"Host": "rebind.example", "Origin": "http://rebind.example"}, event)[0]
            == 403
        )
        assert _get(web_port, base + "event", {"Host": own, "Origin": "http://evil.example"}, event)[0] == 403
        assert _get(web_port, base + "event", {"Host": own, "Origin": f"http://{own}"}, event)[0] == 200
        _wait_for(out, r"clicked: ", app)

        # the bag ends; the page stays until Ctrl-C
        _wait_for(err, r"the bag has ended; still serving until Ctrl-C", app)
        time.sleep(1.0)
        assert app.poll() is None and _get(web_port, base)[0] == 200
        app.send_signal(signal.SIGINT)
        assert app.wait(timeout=60) == 0
    finally:
        if app.poll() is None:
            app.kill()
            app.wait()
    stdout, stderr = out.read_bytes(), err.read_bytes()
    for text in (stdout, stderr):
        assert b"\x1b" not in text and b"\x07" not in text and b"Traceback" not in text
    assert stdout.count(b"clicked: ") == 1 and b"\\x1b[2A" in stdout  # the one event let in, its frame shown
    assert stderr.count(b"cannot keep the compressed viewer") == 1


def test_followers_that_left_an_idle_recording_free_their_places(tmp_path: Path) -> None:
    """Issue 44, item 12: 16 followers of ``recording.rrd`` (MAX_SERVING) read some of it and go, while the
    recording is idle (the bag has ended): the page was 503 from then on, until new data came (none would); now a
    gone follower is seen within a second and the page answers."""
    import socket

    from r2d2_viz.viewer.web.door import MAX_SERVING

    spec = BagSpec()
    for k in range(5):
        t = T0 + k * 100_000_000
        spec.add("/tf", t, tf_message([(t, "odom", "base_link", [k * 0.1, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])]))
    bag = write_bag(tmp_path / "idle", spec)
    web_port, err = _free_port(), tmp_path / "stderr"
    exe = Path(sys.executable).parent / "r2d2-viz"
    with err.open("wb") as e:
        command = [str(exe), "--bag", str(bag), "--serve", "--web-port", str(web_port)]
        app = subprocess.Popen(
            command, stdout=subprocess.DEVNULL, stderr=e, stdin=subprocess.DEVNULL, start_new_session=True
        )
    try:
        url = _wait_for(err, r"serving: open (\S+) in a browser", app).group(1)
        base = f"/{url.rstrip('/').rsplit('/', 1)[1]}/"
        _wait_for(err, r"the bag has ended; still serving until Ctrl-C", app)
        followers = []
        for _ in range(MAX_SERVING):
            s = socket.create_connection(("127.0.0.1", web_port), timeout=10)
            s.sendall(f"GET {base}recording.rrd HTTP/1.1\r\nHost: 127.0.0.1:{web_port}\r\n\r\n".encode())
            assert s.recv(12).startswith(b"HTTP/1.1 200")
            followers.append(s)
        assert _get(web_port, base)[0] == 503  # every place taken (the followers are there)
        for s in followers:
            s.close()
        statuses = []
        for _ in range(50):  # the followers' waits are a second each: the page answers within a few
            statuses.append(_get(web_port, base)[0])
            if statuses[-1] == 200:
                break
            time.sleep(0.1)
        assert statuses[-1] == 200 and len(statuses) <= 30, statuses
        app.send_signal(signal.SIGINT)
        assert app.wait(timeout=60) == 0
    finally:
        if app.poll() is None:
            app.kill()
            app.wait()
