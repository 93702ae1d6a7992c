"""``r2d2-viz --dataset DIR`` (issue 25): the real CLI serving a folder of fleet recordings through Rerun's catalog
server on loopback — a catalog client sees one segment per recording, keyed by the bag's recording id; it listens
on 127.0.0.1 only; ``--serve`` adds a web viewer, both behind the run's token; Ctrl-C stops both — and bad folders
are one line."""

from __future__ import annotations

import http.client
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import cli, kill_all, listening_addresses
from fleetbags import still_bag
from rerun.chunk import RrdReader

EXE = str(Path(sys.executable).parent / "r2d2-viz")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("fleet")
    bags = [still_bag(root / name, samples=3) for name in ("alpha", "beta")]
    result = cli("--bag", *map(str, bags), "--save-dir", str(root / "out"))
    assert result.returncode == 0, result.stderr
    return root / "out"


def _start(*args: str) -> tuple[subprocess.Popen[str], str]:
    proc = subprocess.Popen(
        [EXE, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    assert proc.stderr is not None
    lines = []
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        lines.append(line)
        if line.startswith("serving dataset") or not line:
            break
    return proc, "".join(lines)


def _stop(proc: subprocess.Popen[str], how: signal.Signals = signal.SIGINT) -> int:
    """Ctrl-C as a terminal sends it (to the whole group), or SIGTERM to the app alone."""
    if how == signal.SIGINT:
        os.killpg(proc.pid, how)
    else:
        proc.send_signal(how)
    return proc.wait(timeout=30)


def test_a_catalog_client_sees_one_segment_per_recording(fleet: Path) -> None:
    from rerun.catalog import CatalogClient

    port = _free_port()
    proc, said = _start("--dataset", str(fleet), "--headless", "--port", str(port))
    try:
        assert f"serving dataset 'out' ({fleet}) at rerun+http://127.0.0.1:{port}" in said, said
        assert listening_addresses(port) == {"127.0.0.1"}
        client = CatalogClient(f"rerun+http://127.0.0.1:{port}")
        dataset = client.get_dataset("out")
        expected = {str(RrdReader(p).recordings()[0].recording_id) for p in fleet.glob("*.rrd")}
        assert set(dataset.segment_ids()) == expected and len(expected) == 2
        # every recording opens on r2d2-viz's layout: the conversion's blueprint, registered as the default
        assert dataset.default_blueprint() is not None and len(dataset.blueprints()) == 1
    finally:
        code = _stop(proc, signal.SIGTERM)
    assert code == 0
    assert not listening_addresses(port)


def test_each_recording_has_its_layout_beside_it(fleet: Path) -> None:
    from rrd import blueprint_components

    for rrd in fleet.glob("*.rrd"):
        layout = blueprint_components(rrd.with_suffix(".rbl"))
        assert layout == blueprint_components(rrd) and any("View" in str(v) for v in layout.values())


def _http(port: int, method: str, path: str, headers: dict[str, str] | None = None, body: bytes | None = None
          ) -> tuple[int, dict[str, str], bytes]:  # fmt: skip
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    try:
        conn.request(method, path, body=body, headers=headers or {})
        response = conn.getresponse()
        return response.status, dict(response.getheaders()), response.read()
    finally:
        conn.close()


FIND_ENTRIES = "/rerun.cloud.v1alpha1.RerunCloudService/FindEntries"
"""A gRPC-web call as Rerun's web viewer sends it to the catalog (seen in headless Chromium, 2026-11-28: WhoAmI,
FindEntries, ReadDatasetEntry, … POSTed to the catalog's origin): an empty message, framed (flag 0, length 0)."""
GRPC_WEB = {"Content-Type": "application/grpc-web+proto", "X-Grpc-Web": "1"}


def test_serve_puts_the_catalog_and_the_web_viewer_behind_the_token(fleet: Path) -> None:
    """Issue 44, item 19: ``--dataset --serve`` served Rerun's catalog (gRPC and gRPC-web) and web viewer to anyone
    who could reach the ports, without a token. Now one port, behind the run's token: without it, neither the
    viewer nor the catalog answers (403, nothing forwarded); the printed address gives the cookie and opens the
    viewer on the catalog there; Ctrl-C stops it all."""
    port, web = _free_port(), _free_port()
    proc, said = _start("--dataset", str(fleet), "--serve", "--port", str(port), "--web-port", str(web))
    try:
        found = re.search(rf"open http://localhost:{web}/([A-Za-z0-9_-]{{32}})/ in a browser", said)
        assert found, said
        token = found.group(1)
        assert listening_addresses(web) == {"127.0.0.1"} and not listening_addresses(port)  # the catalog: inside
        for path, method, headers in [("/", "GET", {}), ("/re_viewer_bg.wasm", "GET", {}),
                                      (FIND_ENTRIES, "POST", GRPC_WEB),
                                      (FIND_ENTRIES, "POST", {**GRPC_WEB, "Cookie": f"r2d2_viz_dataset={token[:-1]}x"}),
                                      (f"/{token[:-1]}x/", "GET", {})]:  # fmt: skip
            status, _, body = _http(web, method, path, headers, b"\0" * 5 if method == "POST" else None)
            assert status == 403 and b"open the address the app printed" in body, (path, status)
        status, headers, _ = _http(web, "GET", f"/{token}/", {"Host": f"localhost:{web}"})
        assert status == 303 and headers["Location"] == f"/?url=rerun%2Bhttp%3A%2F%2Flocalhost%3A{web}"
        cookie = headers["Set-Cookie"]
        assert cookie == f"r2d2_viz_dataset={token}; Path=/; HttpOnly; SameSite=Strict"
        with_token = {"Cookie": cookie.split(";")[0]}
        status, _, page = _http(web, "GET", "/?url=x", with_token)
        assert status == 200 and b"<html>" in page and b"re_viewer" in page  # Rerun's web viewer
        status, headers, answer = _http(web, "POST", FIND_ENTRIES, {**GRPC_WEB, **with_token}, b"\0" * 5)
        assert status == 200 and headers["content-type"] == "application/grpc-web+proto"
        assert b"\x03out" in answer and answer.endswith(b"grpc-status:0\r\n")  # the dataset named after the folder
    finally:
        code = _stop(proc)
    assert code == 0
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and listening_addresses(web):
        time.sleep(0.1)
    assert not listening_addresses(web)


def test_bad_folders_are_one_line(fleet: Path, tmp_path: Path) -> None:
    (tmp_path / "link.rrd").symlink_to(next(fleet.glob("*.rrd")))
    result = cli("--dataset", str(tmp_path), "--headless")
    assert result.returncode == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 2 and "1 symlinked .rrd file(s) the catalog skips" in lines[0]
    assert lines[1] == f"error: --dataset {tmp_path}: no .rrd recordings in it"
    result = cli("--dataset", str(fleet), env={"DISPLAY": "", "WAYLAND_DISPLAY": ""})
    assert result.returncode == 2 and "--spawn: no display" in result.stderr
    result = cli("--dataset", str(fleet), "--bag", str(fleet))
    assert result.returncode == 2 and "--bag goes with --save-dir" in result.stderr


def test_the_example_sums_up_the_fleet(fleet: Path, tmp_path: Path) -> None:
    example = Path(__file__).resolve().parents[2] / "examples" / "fleet_summary.py"
    result = subprocess.run(
        [sys.executable, str(example), str(fleet), "--csv", str(tmp_path / "f.csv")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    # still_bag: no transforms, so the base never moves (0 m); 3 samples 0.1 s apart
    assert result.stdout.splitlines()[0] == "2 runs, 0.00 h, the robots' bases travelled 0.0 m in all"
    assert "alpha" in result.stdout and "beta" in result.stdout and (tmp_path / "f.csv").exists()


def _sigint_ignored() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # as `nohup … &` and CI runners start it


def test_sigterm_leaves_no_web_viewer_behind(fleet: Path) -> None:
    """Issue 36, finding 4: ``--dataset --serve`` stopped with SIGTERM left Rerun's web viewer holding its port
    (the console script in front of the viewer binary died, the binary lived on with parent 1)."""
    import psutil

    port, web = _free_port(), _free_port()
    proc = subprocess.Popen(
        [EXE, "--dataset", str(fleet), "--serve", "--port", str(port), "--web-port", str(web)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=_sigint_ignored,
    )
    assert proc.stderr is not None
    said = ""
    while not said.startswith("serving dataset"):
        said = proc.stderr.readline()
        assert said, "the app ended before serving"
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and not listening_addresses(web):
        time.sleep(0.1)
    children = psutil.Process(proc.pid).children(recursive=True)
    try:
        assert listening_addresses(web) and children
        assert _stop(proc, signal.SIGTERM) == 0
        _, alive = psutil.wait_procs(children, timeout=15)
        assert [p for p in alive if p.status() != psutil.STATUS_ZOMBIE] == []
        assert not listening_addresses(web) and not listening_addresses(port)
    finally:
        kill_all(proc, children)


def test_a_busy_web_port_is_one_line(fleet: Path) -> None:
    """Issue 36, finding 4: it said "serving" while its web viewer had died on the busy port."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        web = taken.getsockname()[1]
        result = cli("--dataset", str(fleet), "--serve", "--port", str(_free_port()), "--web-port", str(web))
    assert result.returncode == 2, result.stderr
    assert result.stderr.splitlines() == [
        f"error: --serve: cannot listen on 127.0.0.1:{web} for the web viewer: Address already in use; "
        "choose another port with --web-port PORT"
    ]
    assert "serving" not in result.stderr
