"""``r2d2-viz --dataset DIR --serve`` in headless Chromium (issue 44, item 19): the printed address (with the run's
token) opens Rerun's web viewer on the catalog through the one door — its files and its gRPC-web calls to the
catalog all answered (none refused for want of the token: the cookie the address set travels with them), up to
its reading the catalog's entries and the dataset's — while a browser context that never opened the address gets
nothing."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import cli
from fleetbags import still_bag

from . import viewers

pytestmark = [pytest.mark.e2e, pytest.mark.slow]


def test_the_dataset_opens_in_the_browser_through_the_token(chromium_browser, tmp_path: Path) -> None:
    bags = [still_bag(tmp_path / name, samples=3) for name in ("alpha", "beta")]
    assert cli("--bag", *map(str, bags), "--save-dir", str(tmp_path / "out")).returncode == 0
    web = viewers.free_port()
    exe = Path(sys.executable).parent / "r2d2-viz"
    err = tmp_path / "stderr"
    with err.open("wb") as e:
        app = subprocess.Popen([str(exe), "--dataset", str(tmp_path / "out"), "--serve", "--web-port", str(web)],
                               stdout=subprocess.DEVNULL, stderr=e, start_new_session=True)  # fmt: skip
    try:
        deadline = time.monotonic() + 60
        while not (found := re.search(r"open (\S+) in a browser", err.read_text(errors="replace"))):
            assert app.poll() is None and time.monotonic() < deadline, err.read_text(errors="replace")
            time.sleep(0.2)
        url = found.group(1).replace("//localhost:", "//127.0.0.1:")
        stranger = chromium_browser.new_context()
        assert stranger.new_page().goto(f"http://127.0.0.1:{web}/").status == 403  # no token, no viewer
        stranger.close()

        context = chromium_browser.new_context(viewport={"width": 1280, "height": 800})
        context.route("**/*", lambda route: route.continue_() if "127.0.0.1" in route.request.url else route.abort())
        answers: list[tuple[int, str]] = []
        page = context.new_page()
        page.on("response", lambda r: answers.append((r.status, r.url)))
        page.goto(url)
        deadline = time.monotonic() + 150
        while not any(s == 200 and u.endswith("/ScanTable") for s, u in answers):  # the catalog's tables, read
            assert time.monotonic() < deadline, answers
            page.wait_for_timeout(500)
        context.close()
    finally:
        viewers._stop_process_group(app)
    calls = [(s, u.rsplit("/", 1)[1]) for s, u in answers if "RerunCloudService" in u]
    assert {"FindEntries", "ReadDatasetEntry"} <= {name for _, name in calls}
    assert all(s == 200 for s, _ in calls) and not [a for a in answers if a[0] == 403], answers
