"""``--render out.mp4|out.gif``: a run's view as a video, drawn by Rerun's own renderer.

The run is first recorded as ``--save`` would write it (the app's blueprint, an ``--rviz`` config's included) into
a private temporary ``.rrd``; a headless viewer (:mod:`r2d2_viz.viewer.files.render`) then draws the chosen view
at ``fps`` frames a second of the recording's time — frame k at start + k / fps, for every such time before the
recording's end (at least one) — and each frame is encoded with PyAV (:mod:`r2d2_viz.run.video_file`). The video
is written beside its target as ``.NAME.PID.partial`` and renamed when whole: a failed or interrupted render
(Ctrl-C) leaves nothing, and an older video stays until the new one replaces it.
"""

from __future__ import annotations

import dataclasses
import math
import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from r2d2_viz.errors import UsageError
from r2d2_viz.progress import counting_bar
from r2d2_viz.run.video_file import VideoFile, video_suffix
from r2d2_viz.runner import RunConfig, run
from r2d2_viz.viewer.files.render import rendering
from r2d2_viz.viewer.sinks import SinkConfig

S = 1_000_000_000
SOFTWARE_NOTE = "no GPU: rendering with Mesa's lavapipe (software Vulkan) on the CPU, roughly 1-4 frames a second"


@dataclass(frozen=True)
class RenderConfig:
    out: Path
    """The video: ``.mp4`` (H.264) or ``.gif``."""
    size: tuple[int, int] = (1280, 720)
    """Width and height in pixels."""
    fps: float = 30.0
    """Frames per second of the recording's time."""
    view: str | None = None
    """The view's name, or a part of it (None: the layout's 3D view)."""


@dataclass(frozen=True)
class RenderResult:
    out: Path
    frames: int
    seconds: float
    """The recording's time the frames cover (frames / fps)."""
    view: str
    software: bool


def frame_times(start: int, end: int, fps: float) -> list[int]:
    """Frame k at ``start + k / fps`` (ns, rounded), for every such time before ``end`` (and at least one frame):
    a 60 s recording at 2 fps is 120 frames."""
    count = max(1, math.ceil((end - start) * fps / S - 1e-9))
    return [start + round(k * S / fps) for k in range(count)]


def check_out(out: Path) -> None:
    """The video's suffix and folder, before anything is run (:class:`UsageError`, naming the file)."""
    video_suffix(out)
    parent = out.parent if str(out.parent) else Path(".")
    if out.is_dir():
        raise UsageError(f"--render {out}: is a directory; give a file name such as out.mp4")
    if not parent.is_dir():
        raise UsageError(f"--render {out}: directory {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise UsageError(f"--render {out}: directory {str(parent)!r} is not writable")


def _offset_start(config: RunConfig) -> int:
    """With ``--start-offset``, the bag's first receive time plus the offset: the recording also holds the 5 s of
    messages before it that set the scene up (the preroll), which the video skips (0: no offset, or header times,
    whose clock the bag's index does not give)."""
    if config.bag is None or not config.start_offset or config.time != "receive":
        return 0
    from r2d2_viz.sources.bags.bag import open_bag

    with open_bag(config.bag) as bag:
        span = bag.span
    return 0 if span is None else span[0] + round(config.start_offset * S)


def render(
    config: RunConfig,
    video: RenderConfig,
    *,
    say: Callable[[str], None] = lambda _: None,
    said_software: list[bool] | None = None,
) -> RenderResult:
    """Record ``config``'s run, render ``video.view`` of it into ``video.out``. ``say`` gets the one-line notes
    (the CPU fallback, once per ``said_software`` list: a fleet says it once)."""
    check_out(video.out)
    if not (math.isfinite(video.fps) and 0 < video.fps <= 1000):
        raise UsageError(f"--fps must be a number of frames per second in (0, 1000], got {video.fps:g}")
    said = said_software if said_software is not None else [False]
    with tempfile.TemporaryDirectory(prefix="r2d2-viz-render-") as tmp:
        rrd = Path(tmp) / "run.rrd"
        sink = SinkConfig(save=rrd)
        run(dataclasses.replace(config, sink=sink, realtime=False, watch=False))
        with rendering(rrd, video.size, video.view) as renderer:
            assert renderer.span is not None and renderer.view is not None
            if renderer.software and not said[0]:
                said[0] = True
                say(SOFTWARE_NOTE)
            times = frame_times(max(renderer.span.start, _offset_start(config)), renderer.span.end, video.fps)
            partial = video.out.with_name(f".{video.out.name}.{os.getpid()}.partial")
            writer = VideoFile(partial, video.size, video.fps, gif=video_suffix(video.out) == ".gif")
            try:
                with counting_bar(video.out.name, len(times), enabled=config.progress) as step:
                    for t in times:
                        writer.add(renderer.frame(t))
                        if step is not None:
                            step()
                writer.close()
                os.replace(partial, video.out)
            except BaseException:
                writer.abandon()
                partial.unlink(missing_ok=True)
                raise
            return RenderResult(video.out, len(times), len(times) / video.fps, renderer.view.name, renderer.software)
