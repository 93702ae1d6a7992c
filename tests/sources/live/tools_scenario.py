"""RViz's tools against a real ROS 2 node, run INSIDE a loopback-only network namespace (``ros_node.in_netns``).

``nodes/tool_listener.py`` (rclpy) listens to the tools' topics and publishes a map (transient local, in ``map``);
``nodes/tf_peer.py`` publishes ``/tf`` map → odom → base_link; ``r2d2-viz --ros --serve --save app.rrd`` (its fixed
frame: the TF root) serves the page. First two events without the token (they must change nothing), then the tools:
by default :data:`PICKS` and the teleop's events POSTed to the page's event endpoint exactly as the page's
JavaScript sends them (``r2d2_viz/viewer/web/page.js``: ``post()``, the teleop's 10 Hz while held and its zero on
release); with ``--browser`` headless Chromium clicks them in the page (``tests/e2e/web_tools_browser.py``). Waits
until the node has what it should, stops the app and the node, prints one JSON: the answers, the app's stdout and
stderr, what the node received (and, with ``--browser``, the picks the viewer reported and the page's lines).
"""

from __future__ import annotations

import argparse
import json
import re
import signal
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from pathlib import Path
from typing import Any

NODES = Path(__file__).resolve().parent / "nodes"
E2E = Path(__file__).resolve().parents[2] / "e2e"
WEB_PORT = 19090
TF = [
    ["map", "odom", [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
    ["odom", "base_link", [1.0, 2.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
]
"""What ``tf_peer.py`` publishes: a robot at (1, 2) in ``map``."""
FORWARD = {"tool": "Teleop", "linear": 0.5, "angular": 0.0}
"""ArrowUp held at the page's default speeds (page.html: 0.5 m/s)."""
STOP = {"tool": "Teleop", "linear": 0, "angular": 0}
"""What the page sends on release (integers: JavaScript's ``0``)."""
PICKS: list[dict[str, Any]] = [
    {"tool": "Publish Point", "points": [[2.5, -1.25, 0.3]], "entity": "/tools/ground"},
    {"tool": "2D Goal Pose", "points": [[1.0, 2.0, 0.01], [2.0, 3.0, 0.02]], "entity": "/tools/ground"},
    {"tool": "2D Pose Estimate", "points": [[-1.5, 0.5, 0.0], [-1.5, -2.5, 0.0]], "entity": None},
]
"""What the page POSTs for Publish Point, 2D Goal Pose, 2D Pose Estimate (``{tool, points, entity}``: the clicks in
the fixed frame as the viewer reported them); then Teleop (``{tool, linear, angular}``): :data:`FORWARD` every 0.1 s
while held — until the node has a forward twist, as a person holds the key until the robot moves (the first
twist opens the writer, and the node may match it only after a later one replaced it) — then :data:`STOP`."""
FORGED = {"tool": "Publish Point", "points": [[9.0, 9.0, 0.0]], "entity": None}
TELEOP_PERIOD_S = 0.1
"""page.js's TELEOP_PERIOD_MS."""


class Lines:
    """A process's stdout lines, read as they come (a thread), for polling."""

    def __init__(self, process: subprocess.Popen[str]) -> None:
        self.lines: list[str] = []
        assert process.stdout is not None
        self._thread = threading.Thread(target=self._read, args=(process.stdout,), daemon=True)
        self._thread.start()

    def _read(self, stream: Any) -> None:
        for line in stream:
            self.lines.append(line.rstrip("\n"))

    def wait(self, done: Any, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not done(list(self.lines)):
            if time.monotonic() > deadline:
                raise SystemExit(f"tools_scenario: {what} within {timeout:.0f} s; got {self.lines[-10:]}")
            time.sleep(0.05)

    def join(self, timeout: float) -> None:
        self._thread.join(timeout)


def _url(log: Path, app: subprocess.Popen[str], timeout: float = 90) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = re.search(r"serving: open (\S+) in a browser", log.read_text())
        if found:
            return found.group(1)
        if app.poll() is not None:
            raise SystemExit(f"r2d2-viz exited: {log.read_text()[-2000:]}")
        time.sleep(0.1)
    raise SystemExit("r2d2-viz printed no URL")


def post(url: str, event: dict[str, Any]) -> tuple[int, Any]:
    """POST ``event`` as page.js's ``post()`` does; (status, the JSON answer or the text)."""
    request = urllib.request.Request(
        url, data=json.dumps(event).encode(), headers={"Content-Type": "application/json"}, method="POST"
    )
    try:
        with urllib.request.urlopen(request, timeout=10) as response:
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read().decode(errors="replace")


def post_events(page_url: str, moving: Callable[[], bool], timeout: float = 60) -> list[tuple[int, Any]]:
    """:data:`PICKS`, then :data:`FORWARD` at the page's period (a slow answer only makes the next one later) until
    ``moving()`` (at most ``timeout`` seconds), then :data:`STOP`."""
    answers = [post(page_url + "event", event) for event in PICKS]
    deadline = time.monotonic() + timeout
    while not answers[3:] or (not moving() and time.monotonic() < deadline):
        sent = time.monotonic()
        answers.append(post(page_url + "event", FORWARD))
        time.sleep(max(0.0, TELEOP_PERIOD_S - (time.monotonic() - sent)))
    answers.append(post(page_url + "event", STOP))
    return answers


def _twists(lines: list[str]) -> list[dict[str, float]]:
    return [json.loads(line.split(" ", 2)[2]) for line in lines if line.startswith("got /cmd_vel ")]


def _received_all(lines: list[str]) -> bool:
    """Each tool's message arrived, and the teleop's last one (the stop: the reader gets a writer's in order)."""
    twists = _twists(lines)
    stopped = bool(twists) and twists[-1]["linear"] == 0 and twists[-1]["angular"] == 0
    topics = {line.split()[1] for line in lines if line.startswith("got ")}
    return stopped and {"/clicked_point", "/goal_pose", "/initialpose"} <= topics


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ros-python", required=True)
    parser.add_argument("--cli", required=True)
    parser.add_argument("--out", required=True, help="folder for the recording, logs (and screenshots)")
    parser.add_argument("--browser", action="store_true", help="click the tools in headless Chromium")
    args = parser.parse_args()
    out = Path(args.out)
    listener = subprocess.Popen(
        [args.ros_python, str(NODES / "tool_listener.py"), "--ready-when", "/tf"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    heard = Lines(listener)
    tf = subprocess.Popen([sys.executable, str(NODES / "tf_peer.py"), "300", "/tf", json.dumps(TF)])
    result: dict[str, Any] = {}
    app = None
    log, stdout = out / "app.log", out / "app.stdout"
    try:
        # the node up and /tf flowing (the node sees its publisher) before the app settles: its root is the frame
        heard.wait(lambda lines: "ready" in lines, 120, "the node was not ready")
        with log.open("w") as err, stdout.open("w") as sink:
            app = subprocess.Popen(
                [args.cli, "--ros", "--serve", "--save", str(out / "app.rrd"), "--duration", "240", "--port", "19876",
                 "--web-port", str(WEB_PORT)],
                stdout=sink, stderr=err, text=True, start_new_session=True,
            )  # fmt: skip
        url = _url(log, app)

        def moving() -> bool:
            return any(t["linear"] != 0 or t["angular"] != 0 for t in _twists(list(heard.lines)))

        token = url.rstrip("/").rsplit("/", 1)[1]
        result["no_token"] = [
            post(f"http://127.0.0.1:{WEB_PORT}{path}", FORGED)[0] for path in ("/event", f"/{token[:-2]}xx/event")
        ]
        if args.browser:
            sys.path.insert(0, str(E2E))
            from web_tools_browser import use_tools

            result.update(use_tools(url, out, moving))
        else:
            result["answers"] = post_events(url, moving)
        heard.wait(_received_all, 60, "the node did not receive every tool's message")
    finally:
        print(f"stopping the app at {time.monotonic():.1f}", file=sys.stderr, flush=True)
        if app is not None:
            if app.poll() is None:
                app.send_signal(signal.SIGINT)
            try:
                app.wait(timeout=60)
            except subprocess.TimeoutExpired:
                app.kill()
        tf.terminate()
        tf.wait(timeout=30)
        listener.send_signal(signal.SIGINT)
        try:
            listener.wait(timeout=30)
        except subprocess.TimeoutExpired:
            listener.kill()
        heard.join(10)
    got = heard.lines[-1] if heard.lines else ""
    assert listener.stderr is not None
    result["received"] = json.loads(got) if got.startswith("{") else {"error": listener.stderr.read()[-2000:]}
    result["stdout"] = stdout.read_text()
    result["app_rc"] = app.returncode
    result["stderr"] = log.read_text().splitlines()
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
