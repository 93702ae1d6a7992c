"""RViz's tools in r2d2-viz's page against a real ROS 2 node, run INSIDE a loopback-only network namespace.

``nodes/tool_listener.py`` (rclpy) listens and publishes a map (transient local, in ``map``); ``nodes/tf_peer.py``
publishes ``/tf`` map → odom → base_link; ``r2d2-viz --ros --serve --save app.rrd`` (its fixed frame: the TF root)
serves the page;
headless Chromium (Debian's, playwright) uses each tool once in one session: Publish Point, 2D Goal Pose,
2D Pose Estimate (each click moved to, frames waited for, then clicked), Teleop (ArrowUp held, released);
then an event without the token. Prints one JSON: the picks the viewer reported, the page's lines, the app's
stdout, the no-token answer, and what the node received.
"""

from __future__ import annotations

import argparse
import json
import re
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
NODES = HERE.parent / "sources" / "live" / "nodes"
sys.path.insert(0, str(HERE))
from viewers import CHROMIUM_ARGS, CHROMIUM_PATH  # noqa: E402

VIEWPORT = (1280, 800)
TOOLS = (("Publish Point", 1), ("2D Goal Pose", 2), ("2D Pose Estimate", 2))
"""The tools that publish (Measure's line and distance: tests/ros_out/test_tools_out.py, without a browser)."""
SPOTS = ((0.42, 0.78), (0.55, 0.72), (0.35, 0.70), (0.60, 0.85), (0.48, 0.66), (0.30, 0.84))
"""Where the 3D view shows the ground (lower middle), as fractions of the viewport; each click a new spot (a click
on the pixel already selected changes no selection, so the viewer reports nothing)."""
TF = [
    ["map", "odom", [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
    ["odom", "base_link", [1.0, 2.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
]
"""What ``tf_peer.py`` publishes: a robot at (1, 2) in ``map``."""


def _url(log: Path, app: subprocess.Popen[str], timeout: float = 90) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = re.search(r"serving: open (\S+) in a browser", log.read_text())
        if found:
            return found.group(1)
        if app.poll() is not None:
            raise SystemExit(f"r2d2-viz exited: {log.read_text()[-2000:]}")
        time.sleep(0.2)
    raise SystemExit("r2d2-viz printed no URL")


class Driver:
    def __init__(self, page: Any, shots: Path) -> None:
        self.page, self.shots, self.spot = page, shots, 0

    def count(self, what: str) -> int:
        return int(self.page.evaluate(f"window.r2d2.{what}.length"))

    def click_ground(self) -> None:
        """One click that the viewer reports with a position (a new spot each try, five tries: under load a click
        now and then lands on a frame that has no pick yet)."""
        picks = self.count("picks")
        for _ in range(5):
            fx, fy = SPOTS[self.spot % len(SPOTS)]
            self.spot += 1
            x, y = fx * VIEWPORT[0], fy * VIEWPORT[1]
            self.page.mouse.move(x - 15, y - 10)
            time.sleep(1.0)
            self.page.mouse.move(x, y)
            time.sleep(3.0)  # SwiftShader: 0.6-3 s a frame; the pick uses the frame before the click
            self.page.mouse.click(x, y)
            deadline = time.monotonic() + 15
            while time.monotonic() < deadline:
                if self.count("picks") > picks:
                    return
                time.sleep(0.25)
        raise RuntimeError("the viewer reported no picked position")

    def use(self, tool: str, clicks: int) -> None:
        lines = self.count("lines")
        self.page.click(f"button[data-tool='{tool}']")
        for _ in range(clicks):
            self.click_ground()
        self.page.wait_for_function(f"window.r2d2.lines.length > {lines}", timeout=20_000)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ros-python", required=True)
    parser.add_argument("--cli", required=True)
    parser.add_argument("--out", required=True, help="folder for the screenshot and logs")
    args = parser.parse_args()
    out = Path(args.out)
    listener = subprocess.Popen(
        [args.ros_python, str(NODES / "tool_listener.py")], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    tf = subprocess.Popen([sys.executable, str(NODES / "tf_peer.py"), "300", "/tf", json.dumps(TF)])
    time.sleep(3.0)  # /tf flowing before the app settles: its root is the fixed frame
    log = out / "app.log"
    stdout = out / "app.stdout"
    with log.open("w") as err, stdout.open("w") as sink:
        app = subprocess.Popen(
            [args.cli, "--ros", "--serve", "--save", str(out / "app.rrd"), "--duration", "240", "--port", "19876",
             "--web-port", "19090"],
            stdout=sink, stderr=err, text=True, start_new_session=True,
        )  # fmt: skip
    result: dict[str, Any] = {}
    try:
        url = _url(log, app)
        from playwright.sync_api import sync_playwright

        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM_PATH, args=list(CHROMIUM_ARGS))
            page = browser.new_page(viewport={"width": VIEWPORT[0], "height": VIEWPORT[1]})
            started = time.monotonic()
            page.goto(url)
            page.wait_for_function("window.r2d2 && window.r2d2.ready", timeout=120_000)
            result["ready_s"] = time.monotonic() - started
            print(f"ready after {result['ready_s']:.1f} s", file=sys.stderr, flush=True)
            time.sleep(4)  # the first frames with the ground
            drive = Driver(page, out)
            try:
                for tool, clicks in TOOLS:
                    print(f"{time.monotonic() - started:.1f} s: {tool}", file=sys.stderr, flush=True)
                    drive.use(tool, clicks)
            except BaseException:
                page.screenshot(path=str(out / "failed.png"))
                print(json.dumps(page.evaluate("window.r2d2")), file=sys.stderr, flush=True)
                raise
            page.keyboard.down("ArrowUp")
            time.sleep(0.8)
            page.keyboard.up("ArrowUp")
            time.sleep(1.0)
            page.screenshot(path=str(out / "toolbar.png"))
            result["picks"] = page.evaluate("window.r2d2.picks")
            result["lines"] = page.evaluate("window.r2d2.lines")
            browser.close()
        token = url.rstrip("/").rsplit("/", 1)[1]
        forged = json.dumps({"tool": "Publish Point", "points": [[9.0, 9.0, 0.0]]}).encode()
        answers = []
        for path in ("/event", f"/{token[:-2]}xx/event"):
            try:
                urllib.request.urlopen(urllib.request.Request(f"http://127.0.0.1:19090{path}", data=forged), timeout=10)
                answers.append(200)
            except urllib.error.HTTPError as exc:
                answers.append(exc.code)
        result["no_token"] = answers
        time.sleep(1.0)
    finally:
        print(f"stopping the app at {time.monotonic():.1f}", file=sys.stderr, flush=True)
        if app.poll() is None:
            app.send_signal(signal.SIGINT)
        try:
            app.wait(timeout=60)
        except subprocess.TimeoutExpired:
            app.kill()
        print(f"app stopped at {time.monotonic():.1f}", file=sys.stderr, flush=True)
        tf.terminate()
        tf.wait(timeout=30)
        listener.send_signal(signal.SIGINT)
        got, errors = listener.communicate(timeout=30)
    result["received"] = json.loads(got.strip().splitlines()[-1]) if got.strip() else {"error": errors[-2000:]}
    result["stdout"] = stdout.read_text()
    result["app_rc"] = app.returncode
    result["stderr"] = log.read_text().splitlines()
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
