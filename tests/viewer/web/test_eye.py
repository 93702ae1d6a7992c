"""The 3D view's eye read out of the viewer's blueprint (for the pose tools' rays): blueprints written by Rerun's
own SDK with an eye placed by hand; rerun-notebook's installed widget hooked once; the page server's ``eye``
endpoint. (Seen in headless Chromium, 2026-11-26: the blueprint ``WebViewer.save_blueprint`` gives holds the
app's eye, then each new one as the view is orbited, on the ``blueprint`` timeline.)

Issue 44, item 11: one POST of a malformed blueprint ended the whole app (Rerun's reader panics in its Arrow decoder:
SIGABRT), and a blueprint without its footer printed Rerun's warning with a temporary path on every POST.
``tests/data/web/blueprint_aborts_rerun.rbl`` is a blueprint saved by ``rrb.Blueprint(...).save`` (one 3D view, eye
at (1, 2, 3)) with its byte 3087 flipped (``^= 0xff``: an Arrow buffer offset in its 4th message becomes 1.8e17);
the test first shows that Rerun's own reader aborts on it."""

from __future__ import annotations

import http.client
import json
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import rerun.blueprint as rrb
from conftest import REPO

from r2d2_viz.errors import ToolEventError
from r2d2_viz.viewer.web.assets import viewer_static
from r2d2_viz.viewer.web.eye import MAX_BLUEPRINT_BYTES, WIDGET_HOOK, EyeReader, framing_problem, hooked_widget
from r2d2_viz.viewer.web.server import PageServer

ABORTS_RERUN = REPO / "tests" / "data" / "web" / "blueprint_aborts_rerun.rbl"
READ_ALL = """import sys
from rerun.chunk import RrdReader
reader = RrdReader(sys.argv[1])
for store in reader.blueprints():
    for chunk in reader.stream(store=store):
        chunk.to_record_batch()
"""


def _blueprint(tmp_path: Path, *eyes: tuple[float, float, float]) -> bytes:
    views = [rrb.Spatial3DView(origin="/", name=f"3D {k}", eye_controls=rrb.EyeControls3D(position=eye,
             look_target=(0, 0, 0))) for k, eye in enumerate(eyes)]  # fmt: skip
    path = tmp_path / "b.rbl"
    rrb.Blueprint(rrb.Horizontal(*views, rrb.TextDocumentView(origin="/notes"))).save("r2d2-viz", path)
    return path.read_bytes()


@pytest.fixture(scope="module")
def reader() -> Iterator[EyeReader]:
    eyes = EyeReader()
    yield eyes
    eyes.close()


def test_the_eye_of_the_one_3d_view(tmp_path: Path, reader: EyeReader) -> None:
    assert reader.read(_blueprint(tmp_path, (-3.0, 1.0, 5.0))) == (-3.0, 1.0, 5.0)
    assert reader.read(_blueprint(tmp_path, (1.0, 2.0, 3.0), (4.0, 5.0, 6.0))) is None  # which one: unknown
    assert reader.read(_blueprint(tmp_path)) is None  # no 3D view


def test_malformed_blueprints_are_refused_and_the_reader_survives(tmp_path: Path, reader: EyeReader) -> None:
    assert subprocess.run([sys.executable, "-c", READ_ALL, str(ABORTS_RERUN)], capture_output=True).returncode == (
        -signal.SIGABRT
    )  # Rerun's own reader: the process ends
    whole = _blueprint(tmp_path, (-3.0, 1.0, 5.0))
    for blob, why in [
        (b"", "empty"),
        (b"RRF2 not a blueprint, a sentence", "message 1 is of no known kind"),
        (b"RRF2 not a blueprint", "message 1 is cut short"),
        (b"junk" * 10, "no RRF2 header"),
        (whole[:12], "no messages"),
        (whole[:-40], "claims"),  # the footer cut short
        (b"\0" * (MAX_BLUEPRINT_BYTES + 1), "larger than 4 MiB"),
    ]:
        problem = framing_problem(blob)
        assert problem is not None and why in problem, (why, problem)
        with pytest.raises(ToolEventError, match="not a blueprint: "):
            reader.read(blob)
    assert framing_problem(ABORTS_RERUN.read_bytes()) is None  # framed as Rerun frames: only Rerun can tell
    with pytest.raises(ToolEventError, match="not a blueprint Rerun can read"):
        reader.read(ABORTS_RERUN.read_bytes())
    assert reader.read(whole) == (-3.0, 1.0, 5.0)  # a new worker for the next click


def test_the_installed_widget_is_hooked_once() -> None:
    js = (viewer_static() / "widget.js").read_bytes()
    hooked = hooked_widget(js)
    assert hooked.count(WIDGET_HOOK.encode()) == 1 and len(hooked) == len(js) + len(WIDGET_HOOK) - len(
        "this.viewer = new WebViewer();"
    )
    assert hooked_widget(b"export default {};") == b"export default {};"  # another widget: left as it is


def _post(port: int, path: str, body: bytes) -> tuple[int, bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    try:
        conn.request("POST", path, body=body, headers={"Content-Type": "application/octet-stream"})
        response = conn.getresponse()
        return response.status, response.read()
    finally:
        conn.close()


def test_the_page_server_answers_the_eye(tmp_path: Path) -> None:
    server = PageServer(None, "127.0.0.1", 0, config={"fixed_frame": "map"})
    try:
        status, body = _post(server.port, f"/{server.token}/eye", _blueprint(tmp_path, (-3.0, 1.0, 5.0)))
        assert status == 200 and json.loads(body) == {"eye": [-3.0, 1.0, 5.0]}
        assert _post(server.port, f"/{server.token}/eye", b"junk") == (
            400,
            b"eye: not a blueprint: not an RRD stream (no RRF2 header)\n",
        )
        assert _post(server.port, "/eye", b"junk")[0] == 404  # the token, as for every path
    finally:
        server.close()


def test_the_served_app_outlives_malformed_blueprints(tmp_path: Path) -> None:
    """The installed CLI: the app serving the tutorial takes a blueprint that aborts Rerun's reader, and three cut
    short, with a 400 each, nothing in the terminal; it then still reads a good one and stops on Ctrl-C."""
    import socket

    import psutil

    workers: list[psutil.Process] = []
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    err = tmp_path / "stderr"
    exe = Path(sys.executable).parent / "r2d2-viz"
    with err.open("wb") as e:
        app = subprocess.Popen([str(exe), "--serve", "--web-port", str(port)], stdout=subprocess.DEVNULL, stderr=e,
                               stdin=subprocess.DEVNULL, start_new_session=True)  # fmt: skip
    try:
        deadline = time.monotonic() + 90
        while not (found := re.search(r"serving: open (\S+) in a browser", err.read_text(errors="replace"))):
            assert app.poll() is None and time.monotonic() < deadline, err.read_text(errors="replace")
            time.sleep(0.1)
        eye = f"/{found.group(1).rstrip('/').rsplit('/', 1)[1]}/eye"
        said = err.read_text(errors="replace")
        whole = _blueprint(tmp_path, (1.0, 2.0, 3.0))
        assert _post(port, eye, ABORTS_RERUN.read_bytes()) == (400, b"eye: not a blueprint Rerun can read\n")
        for _ in range(3):
            assert _post(port, eye, whole[:-40])[0] == 400
        assert _post(port, eye, whole) == (200, b'{"eye": [1.0, 2.0, 3.0]}')
        assert app.poll() is None
        workers = psutil.Process(app.pid).children()
        assert len(workers) == 1 and "r2d2_viz.viewer.web.eye" in workers[0].cmdline()
        new = err.read_text(errors="replace")[len(said) :]
        assert "RerunWarning" not in new and "r2d2-viz-eye" not in new and "panicked" not in new, new
    finally:
        if app.poll() is None:
            app.send_signal(signal.SIGINT)
        code = app.wait(timeout=30)
    assert code == 0, err.read_text(errors="replace")
    _, alive = psutil.wait_procs(workers, timeout=15)
    assert alive == []  # the worker ended with the app
