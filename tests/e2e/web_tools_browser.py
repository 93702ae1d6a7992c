"""Headless Chromium (Debian's, playwright) using RViz's tools in r2d2-viz's page, for ``--browser`` of
``tests/sources/live/tools_scenario.py`` (inside its network namespace): each tool once in one session — Publish
Point, 2D Goal Pose, 2D Pose Estimate (each click moved to, frames waited for, then clicked), Teleop (ArrowUp held
until the app answered a forward twist, released, until it answered the stop). Every wait polls for what it needs
(a number of the browser's frames, a pick, a line): SwiftShader takes 0.6-3 s a frame, more under load.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from playwright.sync_api import TimeoutError as PlaywrightTimeout
from viewers import CHROMIUM_ARGS, CHROMIUM_PATH

VIEWPORT = (1280, 800)
TOOLS = (("Publish Point", 1), ("2D Goal Pose", 2), ("2D Pose Estimate", 2))
"""The tools that publish (Measure's line and distance: tests/ros_out/test_tools_out.py, without a browser)."""
HOVER_FRAMES = 6
"""Frames drawn after the pointer came to a spot before it clicks there: the viewer picks on the GPU under the
pointer and reads the result back frames later; the click selects what the last read-back found."""
FRAMES = """() => { if (window.r2d2Frames === undefined) { window.r2d2Frames = 0;
  const tick = () => { window.r2d2Frames++; requestAnimationFrame(tick); }; requestAnimationFrame(tick); }
  return window.r2d2Frames; }"""
"""Counts the page's animation frames (a frame in which the viewer draws ends only when its drawing has)."""
SPOTS = ((0.42, 0.78), (0.55, 0.72), (0.35, 0.70), (0.60, 0.85), (0.48, 0.66), (0.30, 0.84))
"""Where the 3D view shows the ground (lower middle), as fractions of the viewport; each click a new spot (a click
on the pixel already selected changes no selection, so the viewer reports nothing)."""


class Driver:
    def __init__(self, page: Any) -> None:
        self.page, self.spot = page, 0

    def frames(self, n: int) -> None:
        """Wait until the browser has drawn ``n`` more frames (at most a minute)."""
        now = int(self.page.evaluate(FRAMES))
        self.page.wait_for_function(f"window.r2d2Frames >= {now + n}", timeout=60_000)

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
            self.frames(1)
            self.page.mouse.move(x, y)
            self.frames(HOVER_FRAMES)
            self.page.mouse.click(x, y)
            try:
                self.page.wait_for_function(f"window.r2d2.picks.length > {picks}", timeout=20_000)
                return
            except PlaywrightTimeout:
                continue
        raise RuntimeError("the viewer reported no picked position")

    def use(self, tool: str, clicks: int) -> None:
        lines = self.count("lines")
        self.page.click(f"button[data-tool='{tool}']")
        for _ in range(clicks):
            self.click_ground()
        self.page.wait_for_function(f"window.r2d2.lines.length > {lines}", timeout=20_000)

    def teleop(self, moving: Callable[[], bool]) -> None:
        """ArrowUp held until the app answered a forward twist and the node has one (``moving()``), as a person
        holds it until the robot moves, then released until the app answered the stop."""
        lines = self.count("lines")
        self.page.keyboard.down("ArrowUp")
        self.page.wait_for_function(
            f"window.r2d2.lines.slice({lines}).some((l) => l.startsWith('teleop: 0.50 m/s'))", timeout=30_000
        )
        deadline = time.monotonic() + 30
        while not moving() and time.monotonic() < deadline:
            time.sleep(0.05)  # the page goes on sending at 10 Hz
        self.page.keyboard.up("ArrowUp")
        self.page.wait_for_function(
            "window.r2d2.lines.length && window.r2d2.lines.at(-1).startsWith('teleop: stopped')", timeout=30_000
        )


def use_tools(url: str, out: Path, moving: Callable[[], bool]) -> dict[str, Any]:
    """Open ``url``, use each tool (``moving()``: the node has a forward twist); the picks the viewer reported,
    the page's lines, seconds until it was ready."""
    from playwright.sync_api import sync_playwright

    result: dict[str, Any] = {}
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM_PATH, args=list(CHROMIUM_ARGS))
        page = browser.new_page(viewport={"width": VIEWPORT[0], "height": VIEWPORT[1]})
        started = time.monotonic()
        page.goto(url)
        page.wait_for_function("window.r2d2 && window.r2d2.ready", timeout=120_000)
        result["ready_s"] = time.monotonic() - started
        print(f"ready after {result['ready_s']:.1f} s", file=sys.stderr, flush=True)
        drive = Driver(page)
        drive.frames(HOVER_FRAMES)  # the first frames with the ground
        try:
            for tool, clicks in TOOLS:
                print(f"{time.monotonic() - started:.1f} s: {tool}", file=sys.stderr, flush=True)
                drive.use(tool, clicks)
            drive.teleop(moving)
        except BaseException:
            page.screenshot(path=str(out / "failed.png"))
            print(json.dumps(page.evaluate("window.r2d2")), file=sys.stderr, flush=True)
            raise
        page.screenshot(path=str(out / "toolbar.png"))
        result["picks"] = page.evaluate("window.r2d2.picks")
        result["lines"] = page.evaluate("window.r2d2.lines")
        browser.close()
    return result
