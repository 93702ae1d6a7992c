"""A recording's view, frame by frame, drawn by Rerun's own renderer without a window (``--render``).

The native viewer runs headless (``rerun --headless``, rerun-sdk 0.41) on a free loopback port and is driven
through its control API (``rerun.experimental.ViewerClient``): it opens the ``.rrd`` with the blueprint the
recording carries (the app's layout, an ``--rviz`` config's included), the chosen view is maximised and the
panels hidden, and each frame is ``set_time`` (paused) then ``take_screenshot`` of that view, which the viewer
answers once it has painted that time. The window is sized so that the view is the asked size; a viewer whose
chrome leaves it a few pixels off is scaled to it.

Without a GPU, wgpu picks Mesa's lavapipe (software Vulkan) by itself; the viewer's own log line says which
adapter draws (``wgpu adapter backend: … device_type: Cpu``), and :attr:`Renderer.software` says so.
"""

from __future__ import annotations

import contextlib
import io
import os
import socket
import subprocess
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from r2d2_viz.errors import R2d2VizError, listed, shown_in_line
from r2d2_viz.viewer.sinks import ends_with_us, viewer_executable

START_S = 60.0
"""How long the viewer may take to listen (lavapipe's first pipeline compiles are slow on a busy machine)."""
SCREENSHOT_TRIES = 3
"""A control call runs out after Rerun's fixed 15 s: a big frame drawn on the CPU beside other work is asked again."""
LAVAPIPE_ICDS = (
    "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json",
    "/usr/share/vulkan/icd.d/lvp_icd.json",
    "/usr/share/vulkan/icd.d/lvp_icd.aarch64.json",
    "/etc/vulkan/icd.d/lvp_icd.x86_64.json",
)
"""Where Debian's mesa-vulkan-drivers puts lavapipe's manifest: offered alone when no other adapter starts."""
SETTLE_S = 30.0
"""At most this long waiting for the view to stop changing before the first frame (toasts fade in ~4 s)."""
SETTLE_SIDE = 320
"""The settling screenshots' longer side: enough to see a toast, cheaper than a frame."""


class RenderError(R2d2VizError):
    """The view cannot be rendered: no such view, no graphics adapter, a viewer that stopped answering."""


class ViewerStartError(RenderError):
    """The headless viewer exited or never listened (no graphics adapter, most often)."""


@dataclass(frozen=True)
class Span:
    """The recording's timeline the frames are taken on: its name, kind and first and last time (ns)."""

    timeline: str
    kind: str  # "duration", "timestamp" or "sequence"
    start: int
    end: int


@dataclass(frozen=True)
class ChosenView:
    view_id: str
    name: str
    kind: str  # the view class: "3D", "2D", "TimeSeries", …


def choose_view(views: list[tuple[str, str, str]], wanted: str | None) -> ChosenView:
    """The view to render among ``(view_id, name, class)``: ``wanted`` by its exact name, else the one whose
    name holds it (any case); None: the first 3D view, else the first view."""
    chosen = [ChosenView(*v) for v in views]
    if not chosen:
        raise RenderError("the recording's layout has no view to render")
    if wanted is None:
        return next((v for v in chosen if v.kind == "3D"), chosen[0])
    exact = [v for v in chosen if v.name == wanted]
    near = exact or [v for v in chosen if wanted.casefold() in v.name.casefold()]
    if len(near) == 1:
        return near[0]
    names = listed(repr(v.name) for v in chosen)
    problem = "names several views" if near else "is not a view of the layout"
    raise RenderError(shown_in_line(f"--view {wanted!r} {problem}; the views: {names}"))


def maximised(blueprint: dict[str, Any], view_id: str) -> dict[str, Any]:
    """``blueprint`` (as ``ViewerClient.get_blueprint`` reads it) with ``view_id`` filling the viewport, the
    blueprint, selection and time panels hidden and the time paused: only the view is drawn."""
    out = dict(blueprint)
    viewport = dict(out.get("/viewport", {}).get("ViewportBlueprint", {}))
    out["/viewport"] = {"ViewportBlueprint": viewport | {"maximized": view_id}}
    for panel in ("/blueprint_panel", "/selection_panel"):
        out[panel] = {"PanelBlueprint": {"state": "Hidden"}}
    time_panel = dict(out.get("/time_panel", {}).get("TimePanelBlueprint", {}))
    out["/time_panel"] = {"TimePanelBlueprint": time_panel | {"state": "Hidden", "play_state": "Paused"}}
    return out


def window_for(size: tuple[int, int], seen: tuple[int, int], window: tuple[int, int]) -> tuple[int, int]:
    """The window that makes the view ``size``: the view was ``seen`` in ``window``; the chrome around it (title
    bar, top panel) stays the same."""
    return (window[0] + size[0] - seen[0], window[1] + size[1] - seen[1])


def png_pixels(png: bytes) -> np.ndarray:
    """A screenshot (PNG) as an HxWx3 uint8 RGB array."""
    from PIL import Image

    with Image.open(io.BytesIO(png)) as image:
        return np.asarray(image.convert("RGB"))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _lavapipe() -> str | None:
    return next((icd for icd in LAVAPIPE_ICDS if Path(icd).is_file()), None)


class Renderer:
    """A headless viewer showing one view of one recording at one size: :meth:`frame` at a time (ns)."""

    def __init__(self, client: Any, log: Path, size: tuple[int, int]) -> None:
        self.client, self.log, self.size = client, log, size
        self.view: ChosenView | None = None
        self.span: Span | None = None

    @property
    def software(self) -> bool:
        """Whether the viewer draws on the CPU (Mesa's lavapipe, or any software adapter)."""
        text = self.log.read_text(errors="replace") if self.log.is_file() else ""
        return any("wgpu adapter backend" in line and "device_type: Cpu" in line for line in text.splitlines())

    def show(self, rrd: Path, wanted: str | None) -> None:
        """Open ``rrd``, choose its view (``wanted``, :func:`choose_view`), maximise it and read the timeline."""
        self.client.open(str(rrd.resolve()))
        state = self.client.get_state()
        self.view = choose_view([(v.view_id, v.name, v.view_class) for v in state.views], wanted)
        recording = next(r for r in state.recordings if r.store_id == state.active_recording)
        self.client.set_blueprint(
            maximised(self.client.get_blueprint().blueprint, self.view.view_id), store_id=recording.store_id
        )
        line = next((t for t in recording.timelines if t.name == recording.current_timeline), None)
        line = line or next((t for t in recording.timelines if t.start is not None), None)
        if line is None or line.start is None or line.end is None:
            raise RenderError(f"{rrd.name}: the recording has no time to render")
        self.span = Span(line.name, line.time_type, line.start, line.end)

    def settle(self, timeout_s: float = SETTLE_S) -> None:
        """Until the view at the first time is drawn alike three times in a row: the viewer's start-up toasts
        ("Listening for gRPC connections…", the adapter it found), drawn over the view for a few seconds, have
        faded, and nothing still loads. After ``timeout_s`` it goes on with what it has."""
        assert self.span is not None
        deadline = time.monotonic() + timeout_s
        shots = [self.frame(self.span.start, size=SETTLE_SIDE)]
        while time.monotonic() < deadline:
            shots = [*shots[-2:], self.frame(self.span.start, size=SETTLE_SIDE)]
            if len(shots) == 3 and all(np.array_equal(shots[0], shot) for shot in shots[1:]):
                return

    def frame(self, t_ns: int, *, size: int | None = None) -> np.ndarray:
        """The view at ``t_ns`` on the span's timeline, as RGB pixels (at most ``size`` on its longer side)."""
        assert self.view is not None and self.span is not None
        span = self.span
        if span.kind == "timestamp":
            self.client.set_time(span.timeline, timestamp=np.datetime64(t_ns, "ns"), play_state="paused")
        elif span.kind == "sequence":
            self.client.set_time(span.timeline, sequence=t_ns, play_state="paused")
        else:
            self.client.set_time(span.timeline, duration=np.timedelta64(t_ns, "ns"), play_state="paused")
        for attempt in range(SCREENSHOT_TRIES):
            try:
                return png_pixels(self.client.take_screenshot(self.view.view_id, max_size=size))
            except (TimeoutError, RuntimeError) as exc:
                if attempt == SCREENSHOT_TRIES - 1:
                    raise RenderError(f"the headless Rerun viewer stopped answering: {exc}") from None
        raise AssertionError("unreachable")


@contextmanager
def _viewer(
    window: tuple[int, int], state: Path, lavapipe: bool
) -> Iterator[tuple[Any, Path, subprocess.Popen[bytes]]]:
    """A headless viewer of ``window`` points, its settings in ``state`` (a fresh machine's: no layout or camera
    from an earlier run), stopped on exit."""
    from rerun.experimental import ViewerClient

    binary = viewer_executable()
    if binary is None:
        raise RenderError("the Rerun viewer binary (rerun-sdk's rerun_cli) was not found")
    port = _free_port()
    env = dict(os.environ, XDG_DATA_HOME=str(state / "data"), XDG_CONFIG_HOME=str(state / "config"))
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    env["RUST_LOG"] = "warn,re_renderer::context=info"  # the adapter line; fewer toasts over the first frames
    icd = _lavapipe() if lavapipe else None
    if icd is not None:
        env |= {"VK_ICD_FILENAMES": icd, "WGPU_BACKEND": "vulkan"}
    command = [binary, "--headless", "--port", str(port), "--bind", "127.0.0.1", "--hide-welcome-screen"]
    command += ["--window-size", f"{window[0]}x{window[1]}"]
    log = state / f"viewer-{port}.log"
    with log.open("wb") as sink:
        proc = subprocess.Popen(
            command, env=env, stdin=subprocess.DEVNULL, stdout=sink, stderr=subprocess.STDOUT, preexec_fn=ends_with_us
        )
    try:
        _wait_listening(proc, port, log)
        try:
            client = ViewerClient.connect(f"rerun+http://127.0.0.1:{port}/proxy")
        except ConnectionError:  # it listened, then found no adapter and exited before we connected (a busy machine)
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=2)
            _wait_listening(proc, port, log)  # exited: a ViewerStartError saying why
            raise
        yield client, log, proc
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _wait_listening(proc: subprocess.Popen[bytes], port: int, log: Path) -> None:
    deadline = time.monotonic() + START_S
    while True:
        if proc.poll() is not None:
            said = log.read_text(errors="replace")
            why = (
                "no graphics adapter (install Mesa's Vulkan drivers: mesa-vulkan-drivers)"
                if "adapter" in said
                else (f"it exited with status {proc.returncode}")
            )
            raise ViewerStartError(f"the headless Rerun viewer did not start: {why}")
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        if time.monotonic() > deadline:
            raise ViewerStartError(f"the headless Rerun viewer did not listen within {START_S:g} s")
        time.sleep(0.1)


@contextmanager
def rendering(rrd: Path, size: tuple[int, int], wanted: str | None) -> Iterator[Renderer]:
    """A :class:`Renderer` of ``rrd``'s view ``wanted`` (None: its 3D view) at ``size`` pixels: a probe viewer
    learns the chrome around the maximised view, then the viewer that renders is sized to leave the view ``size``."""
    with tempfile.TemporaryDirectory(prefix="r2d2-viz-render-") as tmp:
        state = Path(tmp)
        lavapipe = False
        try:
            seen = _probe(rrd, size, wanted, state, lavapipe)
        except ViewerStartError:
            if _lavapipe() is None:
                raise
            lavapipe = True  # no adapter of its own: offer wgpu lavapipe alone
            seen = _probe(rrd, size, wanted, state, lavapipe)
        window = window_for(size, seen, size)
        with _viewer(window, state, lavapipe) as (client, log, _proc):
            renderer = Renderer(client, log, size)
            renderer.show(rrd, wanted)
            renderer.settle()
            yield renderer


def _probe(rrd: Path, size: tuple[int, int], wanted: str | None, state: Path, lavapipe: bool) -> tuple[int, int]:
    with _viewer(size, state, lavapipe) as (client, log, proc):
        renderer = Renderer(client, log, size)
        try:
            renderer.show(rrd, wanted)
            assert renderer.span is not None
            height, width = renderer.frame(renderer.span.start).shape[:2]
        except (ConnectionError, RenderError) as exc:  # it listens first, then looks for an adapter
            try:
                proc.wait(timeout=2)
            except subprocess.TimeoutExpired:  # still running: the error is the view's or the recording's
                if isinstance(exc, RenderError):
                    raise exc from None
                raise RenderError(f"the headless Rerun viewer failed: {exc}") from None
            _wait_listening(proc, 0, log)  # it exited: why, as a viewer that never listened
        return width, height
