"""The 3D view's eye read out of the viewer's blueprint (for the pose tools' rays): blueprints written by Rerun's
own SDK with an eye placed by hand; rerun-notebook's installed widget hooked once; the page server's ``eye``
endpoint. (Seen in headless Chromium, 2026-11-26: the blueprint ``WebViewer.save_blueprint`` gives holds the
app's eye, then each new one as the view is orbited, on the ``blueprint`` timeline.)"""

from __future__ import annotations

import http.client
import json
from pathlib import Path

import rerun.blueprint as rrb

from r2d2_viz.viewer.web.assets import viewer_static
from r2d2_viz.viewer.web.eye import MAX_BLUEPRINT_BYTES, WIDGET_HOOK, blueprint_eye, hooked_widget
from r2d2_viz.viewer.web.server import PageServer


def _blueprint(tmp_path: Path, *eyes: tuple[float, float, float]) -> bytes:
    views = [rrb.Spatial3DView(origin="/", name=f"3D {k}", eye_controls=rrb.EyeControls3D(position=eye,
             look_target=(0, 0, 0))) for k, eye in enumerate(eyes)]  # fmt: skip
    path = tmp_path / "b.rbl"
    rrb.Blueprint(rrb.Horizontal(*views, rrb.TextDocumentView(origin="/notes"))).save("r2d2-viz", path)
    return path.read_bytes()


def test_the_eye_of_the_one_3d_view(tmp_path: Path) -> None:
    assert blueprint_eye(_blueprint(tmp_path, (-3.0, 1.0, 5.0))) == (-3.0, 1.0, 5.0)
    assert blueprint_eye(_blueprint(tmp_path, (1.0, 2.0, 3.0), (4.0, 5.0, 6.0))) is None  # which one: unknown
    assert blueprint_eye(_blueprint(tmp_path)) is None  # no 3D view
    assert blueprint_eye(b"RRF2 not a blueprint") is None
    assert blueprint_eye(b"") is None and blueprint_eye(b"\0" * (MAX_BLUEPRINT_BYTES + 1)) is None


def test_the_installed_widget_is_hooked_once() -> None:
    js = (viewer_static() / "widget.js").read_bytes()
    hooked = hooked_widget(js)
    assert hooked.count(WIDGET_HOOK.encode()) == 1 and len(hooked) == len(js) + len(WIDGET_HOOK) - len(
        "this.viewer = new WebViewer();"
    )
    assert hooked_widget(b"export default {};") == b"export default {};"  # another widget: left as it is


def test_the_page_server_answers_the_eye(tmp_path: Path) -> None:
    server = PageServer(9876, "127.0.0.1", 0, config={"fixed_frame": "map"})
    try:

        def post(path: str, body: bytes) -> tuple[int, bytes]:
            conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=60)
            try:
                conn.request("POST", path, body=body, headers={"Content-Type": "application/octet-stream"})
                response = conn.getresponse()
                return response.status, response.read()
            finally:
                conn.close()

        status, body = post(f"/{server.token}/eye", _blueprint(tmp_path, (-3.0, 1.0, 5.0)))
        assert status == 200 and json.loads(body) == {"eye": [-3.0, 1.0, 5.0]}
        assert post(f"/{server.token}/eye", b"junk") == (200, b'{"eye": null}')
        assert post("/eye", b"junk")[0] == 404  # the token, as for every path
    finally:
        server.close()
