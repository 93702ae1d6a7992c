"""Look at what a person sees in the real Rerun viewers (web and native) for an .rrd file.

Everything here is plain functions and context managers; pytest wiring lives in ``conftest.py``.

Web viewer
    ``serve_web_viewer()`` runs ``rerun FILE --web-viewer --web-viewer-port P --port Q --bind 127.0.0.1``
    (the rerun CLI shipped in rerun-sdk), exactly what a user runs, with ``BROWSER`` pointed at
    ``true`` so the CLI does not launch a browser itself. ``screenshot_web()`` then drives Debian's
    Chromium (headless, SwiftShader WebGL2; the viewer's WebGPU probe finds no adapter and it falls
    back to WebGL2 by itself) via playwright-python at the URL the CLI prints,
    ``http://127.0.0.1:P/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3AQ%2Fproxy``.

Native viewer
    ``xvfb()`` starts ``Xvfb -displayfd`` on a free display; ``screenshot_native()`` runs
    ``rerun FILE --screenshot-to OUT.png --window-size WxH`` against it with Mesa's lavapipe
    (software Vulkan) selected through ``VK_ICD_FILENAMES`` and ``WGPU_BACKEND=vulkan``.

Pixel helpers
    ``load_png``, ``color_mask``, ``color_fraction``, ``color_bbox``, ``dominant_color``,
    ``bbox_to_region``. Regions are ``(x0, y0, x1, y1)`` fractions of the image.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import functools
import http.server
import io
import os
import select
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

if TYPE_CHECKING:
    from playwright.sync_api import Browser, Page, Playwright
    from rerun.experimental import ViewerClient

# --------------------------------------------------------------------------------------------------
# Constants / discovery

#: Debian Chromium; override with $E2E_CHROMIUM (e.g. /usr/bin/chromium-browser on other images).
CHROMIUM_PATH = os.environ.get("E2E_CHROMIUM") or "/usr/bin/chromium"

#: Flags for headless Debian Chromium so the viewer gets a (software) WebGL2 context.
#: ``--use-angle=swiftshader`` + ``--enable-unsafe-swiftshader`` give ANGLE-on-SwiftShader WebGL2;
#: the rest keep the browser from phoning home on this offline machine.
CHROMIUM_ARGS: tuple[str, ...] = (
    "--no-sandbox",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-quic",
)

#: Where Debian's mesa-vulkan-drivers puts the lavapipe ICD manifest (first existing one wins).
LAVAPIPE_ICD_CANDIDATES: tuple[str, ...] = (
    "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json",
    "/usr/share/vulkan/icd.d/lvp_icd.json",
    "/usr/share/vulkan/icd.d/lvp_icd.aarch64.json",
    "/etc/vulkan/icd.d/lvp_icd.x86_64.json",
)

RGB = tuple[int, int, int]
Region = tuple[float, float, float, float]
BBox = tuple[int, int, int, int]


def rerun_cli() -> str:
    """The ``rerun`` CLI the app itself uses (:func:`r2d2_viz.viewer.sinks.viewer_executable`)."""
    from r2d2_viz.viewer.sinks import viewer_executable

    found = viewer_executable()
    if found is None:
        raise FileNotFoundError("rerun CLI not found next to the interpreter nor on PATH")
    return found


def lavapipe_icd() -> str | None:
    """Path of Mesa's lavapipe Vulkan ICD manifest, or None when mesa-vulkan-drivers is absent."""
    for cand in LAVAPIPE_ICD_CANDIDATES:
        if Path(cand).is_file():
            return cand
    return None


def missing_web_prerequisites() -> list[str]:
    """Human-readable reasons why the web harness cannot run here (empty list: all present)."""
    reasons: list[str] = []
    if not (Path(CHROMIUM_PATH).is_file() and os.access(CHROMIUM_PATH, os.X_OK)):
        reasons.append(f"Chromium not found at {CHROMIUM_PATH} (apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        reasons.append("python package 'playwright' is not installed (pip install playwright)")
    try:
        rerun_cli()
    except FileNotFoundError as exc:
        reasons.append(str(exc))
    return reasons


def missing_native_prerequisites() -> list[str]:
    """Human-readable reasons why the native harness cannot run here (empty list: all present)."""
    reasons: list[str] = []
    if shutil.which("Xvfb") is None:
        reasons.append("Xvfb not found on PATH (apt-get install xvfb)")
    if lavapipe_icd() is None:
        reasons.append(
            "Mesa lavapipe Vulkan ICD not found in "
            + ", ".join(LAVAPIPE_ICD_CANDIDATES)
            + " (apt-get install mesa-vulkan-drivers)"
        )
    if ctypes.util.find_library("X11") is None:
        reasons.append("libX11 not found (apt-get install libx11-6)")
    try:
        rerun_cli()
    except FileNotFoundError as exc:
        reasons.append(str(exc))
    return reasons


# --------------------------------------------------------------------------------------------------
# Process hygiene


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port on ``host`` that was free a moment ago (bind to port 0, read it, close)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def _stop_process_group(proc: subprocess.Popen[Any], grace: float = 5.0) -> None:
    """SIGTERM then SIGKILL the process group led by ``proc`` (started with start_new_session)."""
    if proc.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            pass
    # Children (e.g. the rerun binary behind the python `rerun` wrapper) may outlive the leader.
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGKILL)
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(timeout=grace)


def _tail(path: Path, n: int = 40) -> str:
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError:
        return "<no log>"
    return "\n".join(lines[-n:])


def _wait_for_tcp(host: str, port: int, deadline: float, proc: subprocess.Popen[Any], log: Path) -> None:
    while True:
        if proc.poll() is not None:
            raise RuntimeError(f"process exited with {proc.returncode} before listening on {port}:\n{_tail(log)}")
        with contextlib.suppress(OSError), socket.create_connection((host, port), timeout=1.0):
            return
        if time.monotonic() > deadline:
            raise TimeoutError(f"nothing listening on {host}:{port} in time:\n{_tail(log)}")
        time.sleep(0.1)


# --------------------------------------------------------------------------------------------------
# Web viewer


@dataclass(frozen=True)
class WebViewerServer:
    """A running ``rerun FILE --web-viewer`` (or http-source variant)."""

    url: str  #: page to open: the web viewer with ``?url=`` pointing at the data source
    web_port: int
    grpc_port: int | None  #: None in ``source="http"`` mode
    pid: int
    log_path: Path


class _CORSFileHandler(http.server.SimpleHTTPRequestHandler):
    def end_headers(self) -> None:
        self.send_header("Access-Control-Allow-Origin", "*")
        super().end_headers()

    def log_message(self, format: str, *args: Any) -> None:
        pass


@contextlib.contextmanager
def _http_file_server(directory: Path) -> Iterator[int]:
    handler = functools.partial(_CORSFileHandler, directory=str(directory))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, name="rrd-http", daemon=True)
    thread.start()
    try:
        yield int(server.server_address[1])
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)


@contextlib.contextmanager
def serve_web_viewer(
    rrd: Path,
    *,
    source: Literal["grpc", "http"] = "grpc",
    log_path: Path | None = None,
    startup_timeout: float = 30.0,
) -> Iterator[WebViewerServer]:
    """Host the Rerun web viewer for ``rrd`` on loopback; stop it (whole process group) on exit.

    ``source="grpc"`` (default) is what a user gets from ``rerun FILE --web-viewer``: the CLI loads
    the file into its gRPC proxy and the page streams it from ``rerun+http://…/proxy``.
    NOTE: with rerun 0.41 that server keeps one CPU core busy for as long as it lives (a tokio
    thread spins in ``LogReceiverSet::recv`` once the file is read). On the 2-core dev box that did
    not measurably slow the toy test down (~33 s either way), but it is one core less for Chromium.
    ``source="http"`` serves the .rrd from an in-process HTTP server instead and runs
    ``rerun http://127.0.0.1:H/FILE.rrd --web-viewer …``; the CLI then only hosts the viewer and the
    page fetches the file itself (``?url=http://…/FILE.rrd``). Same viewer, same blueprint, idle server.
    """
    rrd = Path(rrd).resolve()
    if not rrd.is_file():
        raise FileNotFoundError(rrd)
    web_port = free_port()
    grpc_port = free_port()
    own_log = log_path is None
    if log_path is None:
        fd, name = tempfile.mkstemp(prefix="rerun-web-", suffix=".log")
        os.close(fd)
        log_path = Path(name)

    env = dict(os.environ)
    # The CLI opens the page with the `webbrowser` crate, which honours $BROWSER: make it a no-op.
    env["BROWSER"] = shutil.which("true") or "/bin/true"
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)

    with contextlib.ExitStack() as stack:
        if own_log:
            stack.callback(lambda: log_path.unlink(missing_ok=True))
        if source == "http":
            http_port = stack.enter_context(_http_file_server(rrd.parent))
            data_url = f"http://127.0.0.1:{http_port}/{urllib.parse.quote(rrd.name)}"
            target = data_url
        elif source == "grpc":
            data_url = f"rerun+http://127.0.0.1:{grpc_port}/proxy"
            target = str(rrd)
        else:
            raise ValueError(f"unknown source {source!r}")
        cmd = [
            rerun_cli(),
            target,
            "--web-viewer",
            "--web-viewer-port",
            str(web_port),
            "--port",
            str(grpc_port),
            "--bind",
            "127.0.0.1",
        ]
        log_file = stack.enter_context(open(log_path, "wb"))
        proc = subprocess.Popen(
            cmd,
            stdin=subprocess.DEVNULL,
            stdout=log_file,
            stderr=subprocess.STDOUT,
            env=env,
            start_new_session=True,
        )
        stack.callback(_stop_process_group, proc)
        deadline = time.monotonic() + startup_timeout
        _wait_for_tcp("127.0.0.1", web_port, deadline, proc, log_path)
        if source == "grpc":
            _wait_for_tcp("127.0.0.1", grpc_port, deadline, proc, log_path)
        url = f"http://127.0.0.1:{web_port}/?url={urllib.parse.quote(data_url, safe='')}"
        yield WebViewerServer(
            url=url,
            web_port=web_port,
            grpc_port=grpc_port if source == "grpc" else None,
            pid=proc.pid,
            log_path=log_path,
        )


@dataclass
class WebShot:
    """Result of ``screenshot_web``."""

    path: Path
    seconds: float  #: from page.goto to the accepted screenshot
    renderer: str | None  #: the viewer's "wgpu adapter backend: …" console line, if seen
    console_errors: list[str] = field(default_factory=list)
    stages: dict[str, float] = field(default_factory=dict)  #: readiness stage -> seconds after goto


def _is_loopback_url(url: str) -> bool:
    parsed = urllib.parse.urlparse(url)
    if parsed.scheme in ("data", "blob", "about"):
        return True
    return parsed.hostname in ("127.0.0.1", "localhost", "::1")


def launch_chromium(pw: Playwright, *, extra_args: Sequence[str] = ()) -> Browser:
    """Debian Chromium, headless, with the software-WebGL flags in ``CHROMIUM_ARGS``."""
    return pw.chromium.launch(
        executable_path=CHROMIUM_PATH,
        headless=True,
        args=[*CHROMIUM_ARGS, *extra_args],
    )


def _decode_png(png: bytes) -> np.ndarray:
    from PIL import Image

    with Image.open(io.BytesIO(png)) as im:
        return np.asarray(im.convert("RGB"))


def changed_fraction(a: np.ndarray, b: np.ndarray, threshold: int = 24) -> float:
    """Fraction of pixels whose largest channel difference exceeds ``threshold`` (1.0 if shapes differ)."""
    if a.shape != b.shape:
        return 1.0
    diff = np.abs(a.astype(np.int16) - b.astype(np.int16)).max(axis=-1)
    return float((diff > threshold).mean())


class ViewerNotReadyError(TimeoutError):
    """The web viewer did not reach the loaded-and-settled state in time."""

    def __init__(self, message: str, *, last_png: bytes | None, stages: dict[str, float]) -> None:
        super().__init__(message)
        self.last_png = last_png
        self.stages = stages


_JS_STATE = """() => {
  const h = window._handle;
  if (h === undefined) return {started: false, panicked: false, recording_bytes: -1, panic: null};
  let panicked = false, panic = null, bytes = -1;
  try { panicked = h.has_panicked(); if (panicked) panic = String(h.panic_message()); } catch (e) {}
  if (!panicked) { try { bytes = h.save_recording().length; } catch (e) { bytes = -1; } }
  return {started: true, panicked: panicked, recording_bytes: bytes, panic: panic};
}"""


def wait_until_viewer_ready(
    page: Page,
    *,
    timeout: float = 90.0,
    poll_interval: float = 1.0,
    stable_polls: int = 2,
    max_changed: float = 0.001,
    ready: Callable[[np.ndarray], bool] | None = None,
    stages: dict[str, float] | None = None,
    t0: float | None = None,
    frames_dir: Path | None = None,
) -> bytes:
    """Poll (bounded by ``timeout``) until the web viewer shows a loaded, settled recording.

    Readiness, in order (each stage's time is recorded in ``stages``):
      1. ``app_started``: ``window._handle`` exists — index.html sets it in ``on_app_started``
         once the wasm app is running (the canvas is visible, the HTML loading text is gone).
         ``_handle.has_panicked()`` is checked on every poll and raises with the panic message.
      2. ``recording_active``: ``_handle.save_recording()`` returns bytes; it throws while the
         viewer has no active recording (welcome screen, or data not yet arrived).
      3. ``stable``: ``stable_polls`` consecutive screenshots, ``poll_interval`` apart, differ in
         at most ``max_changed`` of their pixels (layout settled, meshes uploaded, playback at its end).
      4. ``predicate`` (only if ``ready`` is given): ``ready(pixels)`` is true for the last screenshot.
    Returns the accepted screenshot (PNG bytes). Raises TimeoutError naming the stage reached.
    ``frames_dir``: if given, every polled screenshot is saved there (``poll_<seconds>.png``).
    """
    t0 = time.monotonic() if t0 is None else t0
    stages = {} if stages is None else stages
    deadline = time.monotonic() + timeout
    prev: np.ndarray | None = None
    streak = 0
    last_png: bytes | None = None
    while True:
        state = page.evaluate(_JS_STATE)
        if state["panicked"]:
            raise RuntimeError(f"Rerun web viewer panicked: {state['panic']}")
        if state["started"]:
            stages.setdefault("app_started", time.monotonic() - t0)
        if state["recording_bytes"] > 0:
            stages.setdefault("recording_active", time.monotonic() - t0)
        if "recording_active" in stages:
            png = page.screenshot()
            last_png = png
            if frames_dir is not None:
                Path(frames_dir).mkdir(parents=True, exist_ok=True)
                (Path(frames_dir) / f"poll_{time.monotonic() - t0:06.1f}.png").write_bytes(png)
            img = _decode_png(png)
            if prev is not None and changed_fraction(img, prev) <= max_changed:
                streak += 1
            else:
                streak = 0
            prev = img
            if streak >= stable_polls - 1:
                stages.setdefault("stable", time.monotonic() - t0)
                if ready is None or ready(img):
                    if ready is not None:
                        stages.setdefault("predicate", time.monotonic() - t0)
                    return png
        if time.monotonic() > deadline:
            reached = max(stages, key=lambda k: stages[k]) if stages else "page_loaded"
            raise ViewerNotReadyError(
                f"web viewer not ready after {timeout:.0f}s; last stage reached: {reached}",
                last_png=last_png if last_png is not None else page.screenshot(),
                stages=dict(stages),
            )
        time.sleep(poll_interval)


def screenshot_web(
    rrd: Path,
    out_png: Path,
    *,
    browser: Browser | None = None,
    viewport: tuple[int, int] = (1280, 800),
    color_scheme: Literal["dark", "light"] = "dark",
    renderer: Literal["webgl", "webgpu"] | None = None,
    source: Literal["grpc", "http"] = "grpc",
    timeout: float = 90.0,
    ready: Callable[[np.ndarray], bool] | None = None,
    stable_polls: int = 2,
    max_changed: float = 0.001,
    log_dir: Path | None = None,
    frames_dir: Path | None = None,
) -> WebShot:
    """Open ``rrd`` in the real Rerun web viewer in headless Chromium and save a PNG of the page.

    ``browser``: reuse a launched playwright Browser (a fresh context is made per call); if None,
    playwright and Chromium are started and stopped here. ``color_scheme`` is the page's
    ``prefers-color-scheme``: the viewer follows it (light UI chrome in "light"; the default dark
    matches the native viewer). ``renderer`` forces ``&renderer=`` (None: viewer's own choice,
    which on SwiftShader is WebGL2 after the WebGPU probe finds no adapter). Requests to anything
    but loopback (Google Fonts, telemetry, examples manifest, GitHub release check) are aborted so
    the run is hermetic and never waits on a network timeout. On timeout, the last screenshot is
    still written to ``out_png`` before ``ViewerNotReadyError`` (a TimeoutError) propagates.
    ``ready``, ``stable_polls``, ``max_changed``: see ``wait_until_viewer_ready``. With the default
    ``max_changed`` a playing timeline counts as "not settled" (the time cursor moves), so the
    screenshot shows the end of playback; SwiftShader plays only a few steps per second.
    """
    out_png = Path(out_png)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    log_path = None if log_dir is None else Path(log_dir) / (out_png.stem + ".rerun.log")
    with contextlib.ExitStack() as stack:
        server = stack.enter_context(serve_web_viewer(rrd, source=source, log_path=log_path))
        if browser is None:
            from playwright.sync_api import sync_playwright

            pw = stack.enter_context(sync_playwright())
            browser = launch_chromium(pw)
            stack.callback(browser.close)
        context = browser.new_context(
            viewport={"width": viewport[0], "height": viewport[1]},
            device_scale_factor=1,
            color_scheme=color_scheme,
        )
        stack.callback(context.close)
        # playwright's own 30 s (a screenshot of a big page on SwiftShader, beside other work) is not ours to
        # choose: every step is bounded by this call's timeout
        context.set_default_timeout(timeout * 1000)
        context.route(
            "**/*",
            lambda route: route.continue_() if _is_loopback_url(route.request.url) else route.abort(),
        )
        page = context.new_page()
        console_errors: list[str] = []
        renderer_line: list[str] = []

        def on_console(msg: Any) -> None:
            text = str(msg.text)
            if "wgpu adapter backend:" in text and not renderer_line:
                renderer_line.append(text.strip())
            if msg.type == "error":
                console_errors.append(text[:500])

        page.on("console", on_console)
        page.on("pageerror", lambda exc: console_errors.append(f"pageerror: {exc}"[:500]))
        url = server.url + (f"&renderer={renderer}" if renderer else "")
        stages: dict[str, float] = {}
        t0 = time.monotonic()
        page.goto(url, wait_until="load", timeout=timeout * 1000)
        stages["page_loaded"] = time.monotonic() - t0
        try:
            png = wait_until_viewer_ready(
                page,
                timeout=max(1.0, timeout - stages["page_loaded"]),
                ready=ready,
                stable_polls=stable_polls,
                max_changed=max_changed,
                stages=stages,
                t0=t0,
                frames_dir=frames_dir,
            )
        except TimeoutError as exc:
            if isinstance(exc, ViewerNotReadyError) and exc.last_png:
                out_png.write_bytes(exc.last_png)
            raise
        out_png.write_bytes(png)
        return WebShot(
            path=out_png,
            seconds=time.monotonic() - t0,
            renderer=renderer_line[0] if renderer_line else None,
            console_errors=console_errors,
            stages=stages,
        )


# --------------------------------------------------------------------------------------------------
# Native viewer


@dataclass(frozen=True)
class XDisplay:
    display: str  #: e.g. ":3"
    width: int
    height: int
    pid: int


def warp_pointer(display: str, x: int, y: int) -> None:
    """Move the X pointer (Xvfb parks it mid-screen, where egui would show hover tooltips)."""
    lib = ctypes.util.find_library("X11")
    if lib is None:
        raise RuntimeError("libX11 not found")
    x11 = ctypes.CDLL(lib)
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    x11.XDefaultRootWindow.restype = ctypes.c_ulong
    x11.XDefaultRootWindow.argtypes = [ctypes.c_void_p]
    x11.XWarpPointer.argtypes = [
        ctypes.c_void_p,  # Display*
        ctypes.c_ulong,  # src_w (None)
        ctypes.c_ulong,  # dest_w (root)
        ctypes.c_int,  # src_x
        ctypes.c_int,  # src_y
        ctypes.c_uint,  # src_width
        ctypes.c_uint,  # src_height
        ctypes.c_int,  # dest_x
        ctypes.c_int,  # dest_y
    ]
    x11.XSync.argtypes = [ctypes.c_void_p, ctypes.c_int]
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    dpy = x11.XOpenDisplay(display.encode())
    if not dpy:
        raise RuntimeError(f"cannot open X display {display}")
    try:
        root = x11.XDefaultRootWindow(dpy)
        x11.XWarpPointer(dpy, 0, root, 0, 0, 0, 0, int(x), int(y))
        x11.XSync(dpy, 0)
    finally:
        x11.XCloseDisplay(dpy)


@contextlib.contextmanager
def xvfb(width: int = 3000, height: int = 2000, *, startup_timeout: float = 15.0) -> Iterator[XDisplay]:
    """Start ``Xvfb`` on a display number it picks itself (``-displayfd``); stop it on exit.

    The default screen is larger than the 2x-scaled window ``--screenshot-to`` makes for a
    1280x800 ``--window-size`` (2560x1600 physical), and the pointer is parked in the bottom-right
    corner, outside that window, so no hover tooltip ends up in the screenshot.
    """
    xvfb_bin = shutil.which("Xvfb")
    if xvfb_bin is None:
        raise FileNotFoundError("Xvfb")
    rfd, wfd = os.pipe()
    try:
        proc = subprocess.Popen(
            [xvfb_bin, "-displayfd", str(wfd), "-screen", "0", f"{width}x{height}x24", "-nolisten", "tcp"],
            pass_fds=(wfd,),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
    finally:
        os.close(wfd)
    try:
        buf = b""
        deadline = time.monotonic() + startup_timeout
        while not buf.endswith(b"\n"):
            remaining = deadline - time.monotonic()
            if remaining <= 0 or proc.poll() is not None:
                raise RuntimeError(f"Xvfb did not report a display (rc={proc.poll()})")
            ready_fds, _, _ = select.select([rfd], [], [], remaining)
            if ready_fds:
                chunk = os.read(rfd, 64)
                if not chunk:
                    raise RuntimeError(f"Xvfb closed -displayfd without a display (rc={proc.poll()})")
                buf += chunk
        display = f":{int(buf.strip())}"
        warp_pointer(display, width - 1, height - 1)
        yield XDisplay(display=display, width=width, height=height, pid=proc.pid)
    finally:
        os.close(rfd)
        _stop_process_group(proc)


def native_render_env(display: str, base: Mapping[str, str] | None = None) -> dict[str, str]:
    """Environment for the native viewer on ``display`` rendering with lavapipe (software Vulkan).

    DISPLAY=<xvfb>; VK_ICD_FILENAMES=<lvp_icd json> (only lavapipe is offered to the Vulkan loader);
    WGPU_BACKEND=vulkan; WAYLAND_DISPLAY unset (winit must pick X11); XDG_RUNTIME_DIR set to a
    private dir when missing (silences winit/xkb "XDG_RUNTIME_DIR is invalid" errors).
    """
    env = dict(os.environ if base is None else base)
    icd = lavapipe_icd()
    if icd is None:
        raise FileNotFoundError("lavapipe ICD (mesa-vulkan-drivers) not found")
    env["DISPLAY"] = display
    env["VK_ICD_FILENAMES"] = icd
    env["WGPU_BACKEND"] = "vulkan"
    env.pop("WAYLAND_DISPLAY", None)
    # a viewer as on a fresh machine: Rerun keeps each application's last layout (camera included) and its
    # settings under XDG_DATA_HOME / XDG_CONFIG_HOME and starts from them; one run's orbiting (a screenshot
    # script, a person) moved the next run's camera, and a native test failed on a machine where nothing changed
    state = tempfile.mkdtemp(prefix="e2e-rerun-state-")
    env["XDG_DATA_HOME"], env["XDG_CONFIG_HOME"] = f"{state}/data", f"{state}/config"
    runtime = env.get("XDG_RUNTIME_DIR")
    if not runtime or not Path(runtime).is_dir():
        runtime_dir = Path(tempfile.gettempdir()) / f"e2e-xdg-runtime-{os.getuid()}"
        runtime_dir.mkdir(mode=0o700, exist_ok=True)
        env["XDG_RUNTIME_DIR"] = str(runtime_dir)
    return env


@contextlib.contextmanager
def native_viewer(display: str, window: tuple[int, int], log: Path, timeout: float = 60.0) -> Iterator[ViewerClient]:
    """The real native viewer on ``display``, driven through its control API; its process group stopped on exit."""
    from rerun.experimental import ViewerClient

    port = free_port()
    command = [
        rerun_cli(),
        "--port",
        str(port),
        "--bind",
        "127.0.0.1",
        "--hide-welcome-screen",
        "--window-size",
        f"{window[0]}x{window[1]}",
        "--renderer",
        "vulkan",
    ]
    with log.open("wb") as sink:
        proc = subprocess.Popen(
            command,
            env=native_render_env(display),
            stdin=subprocess.DEVNULL,
            stdout=sink,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
    try:
        _wait_listening(proc, port, log, timeout)
        yield ViewerClient.connect(f"rerun+http://127.0.0.1:{port}/proxy")
    finally:
        _stop_process_group(proc)


def _wait_listening(proc: subprocess.Popen[bytes], port: int, log: Path, timeout: float) -> None:
    """Until the viewer ``proc`` listens on ``port`` (its log's tail in the error when it exits or times out)."""
    deadline = time.monotonic() + timeout
    while True:
        if proc.poll() is not None:
            raise RuntimeError(f"rerun exited with {proc.returncode}:\n{_tail(log)}")
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        if time.monotonic() > deadline:
            raise TimeoutError(f"rerun did not listen on port {port} within {timeout:.0f} s:\n{_tail(log)}")
        time.sleep(0.2)


@contextlib.contextmanager
def headless_viewer(log: Path, timeout: float = 60.0) -> Iterator[ViewerClient]:
    """The real native viewer with no window (``rerun --headless``: no display needed; lavapipe renders), driven
    through its control API on a free loopback port; its process group stopped on exit."""
    from rerun.experimental import ViewerClient

    port = free_port()
    command = [rerun_cli(), "--headless", "--port", str(port), "--bind", "127.0.0.1", "--hide-welcome-screen"]
    env = native_render_env("")
    env.pop("DISPLAY", None)
    with log.open("wb") as sink:
        proc = subprocess.Popen(
            command, env=env, stdin=subprocess.DEVNULL, stdout=sink, stderr=subprocess.STDOUT, start_new_session=True
        )
    try:
        _wait_listening(proc, port, log, timeout)
        yield ViewerClient.connect(f"rerun+http://127.0.0.1:{port}/proxy")
    finally:
        _stop_process_group(proc)


@dataclass(frozen=True)
class Report:
    """One problem a view reports at one time of the recording."""

    time_ns: int
    view: str
    severity: str
    summary: str


def alike(img: np.ndarray, previous: np.ndarray | None) -> bool:
    """Two screenshots taken apart alike (at most 0.1 % of the pixels changed): the viewer has stopped drawing."""
    return previous is not None and changed_fraction(img, previous) <= 0.001


def save_screenshot(client: ViewerClient, png: Path, tries: int = 3) -> None:
    """``client.save_screenshot(png)``, asked again (``tries`` times in all) when Rerun's control call runs out of
    time: a 4-megapixel frame drawn by lavapipe beside other work has taken longer than its fixed deadline."""
    for attempt in range(tries):
        try:
            client.save_screenshot(str(png))  # type: ignore[attr-defined]
            return
        except TimeoutError:
            if attempt == tries - 1:
                raise


def still_screenshot(client: ViewerClient, png: Path, *, timeout: float = 10.0, interval: float = 0.5) -> np.ndarray:
    """Screenshots of a running native viewer into ``png``, ``interval`` apart, until two are alike (at most 0.1 %
    of the pixels changed: :func:`alike`) or ``timeout`` has passed; the last one's pixels."""
    deadline = time.monotonic() + timeout
    previous: np.ndarray | None = None
    while True:
        save_screenshot(client, png)
        img = load_png(png)
        if alike(img, previous) or time.monotonic() > deadline:
            return img
        previous = img
        time.sleep(interval)


def view_reports(
    client: ViewerClient, rrd: Path, *, samples: int = 9, timeline: str = "time", since_ns: int | None = None
) -> list[Report]:
    """What the views of ``rrd`` report (Rerun's error badges), at ``samples`` times spread evenly over
    ``timeline`` from its first time (or ``since_ns``, when later) to its last, in the recording's own blueprint
    (reset to it: the viewer keeps the blueprint of the app id's last recording otherwise). The recording is
    closed afterwards.

    Each time is waited for with a (tiny) screenshot: the viewer answers it only once it has painted that time,
    so the reports are those of that time."""
    if client.get_state().recordings:
        client.close("all")
    client.open(str(Path(rrd).resolve()))
    try:
        client.run_command("recording.reset_blueprint_to_default")
        state = client.get_state()
        recording = next(r for r in state.recordings if r.store_id == state.active_recording)
        line = next(t for t in recording.timelines if t.name == timeline)
        assert line.start is not None and line.end is not None, line
        out: list[Report] = []
        first = line.start if since_ns is None else min(max(line.start, since_ns), line.end)
        for i in range(samples):
            t = first + (line.end - first) * i // max(samples - 1, 1)
            if line.time_type == "timestamp":
                client.set_time(timeline, timestamp=np.datetime64(t, "ns"), play_state="paused")
            else:
                client.set_time(timeline, duration=np.timedelta64(t, "ns"), play_state="paused")
            client.take_screenshot(max_size=64)
            out += [
                Report(t, view.name, report.severity, report.summary)
                for view in client.get_state().views
                for report in view.reports
            ]
        return out
    finally:
        client.close("all")


@dataclass
class NativeShot:
    """Result of ``screenshot_native``."""

    path: Path
    seconds: float
    adapter: str | None  #: the viewer's "wgpu adapter backend: …" log line
    log: str


def screenshot_native(
    rrd: Path,
    out_png: Path,
    *,
    display: str,
    window_size: tuple[int, int] = (1280, 800),
    timeout: float = 90.0,
    log_path: Path | None = None,
) -> NativeShot:
    """Run ``rerun FILE --screenshot-to OUT --window-size WxH`` on ``display``; return the PNG.

    The viewer renders at 2 pixels per point for screenshots, so the PNG is 2x ``window_size``.
    ``--port <free> --bind 127.0.0.1`` keep its built-in gRPC server off the shared default
    port 9876 and off non-loopback interfaces. The whole process group is killed on timeout.
    """
    rrd = Path(rrd).resolve()
    out_png = Path(out_png).resolve()
    out_png.parent.mkdir(parents=True, exist_ok=True)
    with contextlib.suppress(FileNotFoundError):
        out_png.unlink()
    if log_path is None:
        log_path = out_png.with_suffix(".rerun.log")
    cmd = [
        rerun_cli(),
        str(rrd),
        "--screenshot-to",
        str(out_png),
        "--window-size",
        f"{window_size[0]}x{window_size[1]}",
        "--port",
        str(free_port()),
        "--bind",
        "127.0.0.1",
        "--renderer",
        "vulkan",
    ]
    t0 = time.monotonic()
    with open(log_path, "wb") as log_file:
        proc = subprocess.Popen(
            cmd,
            stdin=subprocess.DEVNULL,
            stdout=log_file,
            stderr=subprocess.STDOUT,
            env=native_render_env(display),
            start_new_session=True,
        )
        try:
            rc = proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            _stop_process_group(proc)
            raise TimeoutError(f"native viewer did not screenshot within {timeout:.0f}s:\n{_tail(log_path)}") from None
        finally:
            _stop_process_group(proc)
    seconds = time.monotonic() - t0
    log = log_path.read_text(errors="replace")
    if rc != 0 or not out_png.is_file():
        raise RuntimeError(f"native viewer failed (rc={rc}, png exists={out_png.is_file()}):\n{_tail(log_path)}")
    adapter = next(
        (ln.split("wgpu adapter backend:", 1)[1].strip() for ln in log.splitlines() if "wgpu adapter backend:" in ln),
        None,
    )
    return NativeShot(path=out_png, seconds=seconds, adapter=adapter, log=log)


# --------------------------------------------------------------------------------------------------
# Pixel helpers


def load_png(path: Path | str) -> np.ndarray:
    """PNG -> HxWx3 uint8 RGB array (alpha dropped)."""
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB")).copy()


def region_slices(shape: Sequence[int], region: Region | None) -> tuple[slice, slice]:
    """Row/column slices for ``region`` = (x0, y0, x1, y1) in fractions of width/height."""
    h, w = int(shape[0]), int(shape[1])
    if region is None:
        return slice(0, h), slice(0, w)
    x0, y0, x1, y1 = region
    if not (0.0 <= x0 < x1 <= 1.0 and 0.0 <= y0 < y1 <= 1.0):
        raise ValueError(f"region must be fractions with x0<x1, y0<y1 in [0, 1]: {region}")
    return slice(round(y0 * h), max(round(y1 * h), round(y0 * h) + 1)), slice(
        round(x0 * w), max(round(x1 * w), round(x0 * w) + 1)
    )


def color_mask(img: np.ndarray, rgb: Sequence[int], tol: int = 8) -> np.ndarray:
    """HxW bool: every channel within ``tol`` of ``rgb``."""
    target = np.asarray(rgb[:3], dtype=np.int16)
    mask: np.ndarray = np.abs(img[..., :3].astype(np.int16) - target).max(axis=-1) <= tol
    return mask


def color_fraction(img: np.ndarray, rgb: Sequence[int], tol: int = 8, region: Region | None = None) -> float:
    """Fraction of pixels (inside ``region``, fractions x0,y0,x1,y1) within ``tol`` of ``rgb``."""
    rows, cols = region_slices(img.shape, region)
    sub = img[rows, cols]
    if sub.size == 0:
        return 0.0
    return float(color_mask(sub, rgb, tol).mean())


def color_bbox(
    img: np.ndarray, rgb: Sequence[int], tol: int = 8, region: Region | None = None, min_pixels: int = 1
) -> BBox | None:
    """Pixel bounding box (x0, y0, x1, y1; x1/y1 exclusive, full-image coordinates) of pixels near
    ``rgb`` inside ``region``; None when fewer than ``min_pixels`` match."""
    rows, cols = region_slices(img.shape, region)
    mask = color_mask(img[rows, cols], rgb, tol)
    if int(mask.sum()) < min_pixels:
        return None
    ys = np.flatnonzero(mask.any(axis=1))
    xs = np.flatnonzero(mask.any(axis=0))
    return (
        int(xs[0]) + cols.start,
        int(ys[0]) + rows.start,
        int(xs[-1]) + 1 + cols.start,
        int(ys[-1]) + 1 + rows.start,
    )


def bbox_to_region(bbox: BBox, shape: Sequence[int]) -> Region:
    """Pixel bbox -> region in fractions (for ``color_fraction(..., region=...)``)."""
    h, w = int(shape[0]), int(shape[1])
    x0, y0, x1, y1 = bbox
    return (x0 / w, y0 / h, x1 / w, y1 / h)


def dominant_color(img: np.ndarray, region: Region | None = None) -> tuple[RGB, float]:
    """Most frequent exact RGB colour in ``region`` and its fraction of that region."""
    rows, cols = region_slices(img.shape, region)
    flat = img[rows, cols].reshape(-1, 3).astype(np.uint32)
    keys = (flat[:, 0] << 16) | (flat[:, 1] << 8) | flat[:, 2]
    values, counts = np.unique(keys, return_counts=True)
    i = int(counts.argmax())
    k = int(values[i])
    return ((k >> 16) & 255, (k >> 8) & 255, k & 255), float(counts[i] / keys.size)
