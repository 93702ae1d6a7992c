"""The page's joint sliders against a real ROS 2 node, run INSIDE a loopback-only network namespace
(``ros_node.in_netns``).

``nodes/joint_states_listener.py`` (rclpy) listens to ``/joint_states``; ``r2d2-viz --ros --urdf URDF --motion sliders
--serve --save app.rrd`` serves the page. Once the node has a message (the sliders where they start), the scenario
POSTs a move of ``tilt`` to −0.3 to the page's event endpoint exactly as the page's JavaScript sends it
(``r2d2_viz/viewer/web/page.js``), waits until the node has :data:`AFTER` messages with the new tilt, stops the app
and the node, and prints one JSON: the answer, every message the node received (in order), the app's exit code and
its output.
"""

from __future__ import annotations

import argparse
import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from tools_scenario import Lines, post

NODES = Path(__file__).resolve().parent / "nodes"
WEB_PORT = 19092
MOVE = {"tool": "Joints", "joint": "tilt", "position": -0.3}
"""What the page POSTs when the slider named ``tilt`` is let go at −0.3."""
AFTER = 8
"""Messages with the new tilt to wait for: enough to count a rate over (10 Hz: about 0.8 s)."""


def _url(paths: tuple[Path, ...], app: subprocess.Popen[str], timeout: float = 90) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for path in paths:
            # --serve's line ("serving: open URL in a browser, ..."), or the sliders' own without --serve
            found = re.search(r"open http://localhost(:\d+/\S+/) in a browser", path.read_text())
            if found:
                return "http://127.0.0.1" + found.group(1)  # the page listens on 127.0.0.1
        if app.poll() is not None:
            raise SystemExit(f"r2d2-viz exited: {paths[0].read_text()[-2000:]}")
        time.sleep(0.1)
    raise SystemExit("r2d2-viz printed no URL")


def _messages(lines: list[str]) -> list[dict[str, Any]]:
    return [json.loads(line.split(" ", 1)[1]) for line in lines if line.startswith("got ")]


def _tilts(lines: list[str]) -> list[float]:
    return [m["position"][m["name"].index("tilt")] for m in _messages(lines) if "tilt" in m["name"]]


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ros-python", required=True)
    parser.add_argument("--cli", required=True)
    parser.add_argument("--urdf", required=True)
    parser.add_argument("--out", required=True, help="folder for the recording and logs")
    args = parser.parse_args()
    out = Path(args.out)
    listener = subprocess.Popen(
        [args.ros_python, str(NODES / "joint_states_listener.py")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    heard = Lines(listener)
    result: dict[str, Any] = {}
    app = None
    log, stdout = out / "app.log", out / "app.stdout"
    try:
        heard.wait(lambda lines: "ready" in lines, 120, "the node was not ready")
        with log.open("w") as err, stdout.open("w") as sink:
            app = subprocess.Popen(
                [args.cli, "--ros", "--urdf", args.urdf, "--motion", "sliders", "--serve", "--save",
                 str(out / "app.rrd"), "--duration", "240", "--port", "19878", "--web-port", str(WEB_PORT)],
                stdout=sink, stderr=err, text=True, start_new_session=True,
            )  # fmt: skip
        url = _url((log, stdout), app)
        # the sliders where they start reach the node before the move: the move is what changes them
        heard.wait(lambda lines: bool(_tilts(lines)), 90, "the node received no /joint_states")
        result["answer"] = post(url + "event", MOVE)
        heard.wait(lambda lines: _tilts(lines).count(-0.3) >= AFTER, 60, f"{AFTER} messages with tilt -0.3")
    finally:
        if app is not None:
            if app.poll() is None:
                app.send_signal(signal.SIGINT)
            try:
                app.wait(timeout=60)
            except subprocess.TimeoutExpired:
                app.kill()
        listener.send_signal(signal.SIGINT)
        try:
            listener.wait(timeout=30)
        except subprocess.TimeoutExpired:
            listener.kill()
        heard.join(10)
    assert listener.stderr is not None
    result["messages"] = _messages(heard.lines)
    result["node_end"] = heard.lines[-1] if heard.lines else listener.stderr.read()[-2000:]
    result["stdout"] = stdout.read_text()
    result["app_rc"] = app.returncode if app is not None else None
    result["stderr"] = log.read_text().splitlines()
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
