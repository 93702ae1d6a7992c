#!/usr/bin/env python3
"""Make the README's pictures from real renders of the native Rerun viewer.

    python scripts/make_screenshots.py [--out docs] [--frames 144] [--fps 15] [--still-time 30] [--bag PATH]

1. records one lap with the installed CLI: ``r2d2-viz --save <tmp>/lap.rrd`` (48 s, 1,440 frames at 30 Hz);
2. starts ONE native ``rerun`` viewer on a private Xvfb display, rendering with Mesa's lavapipe (software
   Vulkan), and opens the recording through the viewer's control API (``rerun.experimental.ViewerClient``);
3. pauses at ``--still-time`` and saves the whole window, the RViz-like layout, as ``r2d2-viz.png``;
4. steps the time cursor through ``--frames`` evenly spaced frames of the lap, screenshots the 3D view
   alone at each, crops all of them to the same box around where the robot goes, and writes the
   animated ``r2d2-viz-lap.gif`` (one shared palette, no dithering, so the still floor compresses away).

The default 144 frames are every 10th recorded frame (1/3 s apart), played at 15 fps: the lap in about
10 s. Far fewer frames alias the tilt (a 2 s back-and-forth) into jumps: with 36 (every 40th frame) the
body jerks between three poses.

5. with ``--bag PATH`` (e.g. the Webots e-puck bag of tests/data/bags/real/webots_epuck), also replays that bag
   (``r2d2-viz --bag PATH --save <tmp>/bag.rrd``), pauses ``--bag-time`` seconds after its first message and
   saves the whole window as ``real-bag.png``: the robot with its sensor data (scans, ranges, odometry).

Nothing is drawn over the renders: the pictures are what the viewer painted, cropped and scaled.
The Xvfb / lavapipe / viewer set-up is the one the e2e tests use (``tests/e2e/viewers.py``), imported
from the checkout. Needs ``xvfb`` and ``mesa-vulkan-drivers`` (Debian) and the venv with r2d2-viz and
Pillow. Every process it starts is stopped by process group on the way out. Takes about four minutes
with lavapipe on two cores (~1.3 s per screenshot).
"""

from __future__ import annotations

import argparse
import io
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
from e2e import viewers  # noqa: E402  (the e2e harness: Xvfb, lavapipe env, process groups)

if TYPE_CHECKING:
    from PIL import Image
    from rerun.experimental import ViewerClient

STILL_NAME = "r2d2-viz.png"
BAG_NAME = "real-bag.png"
GIF_NAME = "r2d2-viz-lap.gif"
TIMELINE = "time"
RATE_HZ = 30.0  # r2d2-viz's default --rate: the lap is frames 0 … 1439 at k / 30 s

Box = tuple[int, int, int, int]  # x0, y0, x1, y1 (exclusive) in pixels


class SetupError(RuntimeError):
    """Something this script needs is missing; the message says what and how to get it."""


# --------------------------------------------------------------------------------------------------
# Pure helpers (no viewer needed)


def lap_times(n_frames_in_lap: int, count: int, rate_hz: float = RATE_HZ) -> list[float]:
    """``count`` evenly spaced frame times (seconds) over the lap, each exactly on a recorded frame."""
    if count < 1:
        raise ValueError("count must be >= 1")
    return [round(i * n_frames_in_lap / count) / rate_hz for i in range(count)]


def robot_mask(img: np.ndarray) -> np.ndarray:
    """Pixels of the robot (white-ish) and of the TF line (saturated) on the grey floor and grid."""
    rgb = img[..., :3].astype(np.int16)
    bright = rgb.min(axis=-1) > 150  # the grid is ~110 grey, the background 48
    saturated = (rgb.max(axis=-1) - rgb.min(axis=-1)) > 60
    mask: np.ndarray = bright | saturated
    return mask


def crop_box(masks: Sequence[np.ndarray], *, margin: float = 0.25, aspect: float = 4 / 3) -> Box:
    """Box around everything any mask marks, grown by ``margin`` (of its size) and to ``aspect``, inside the image."""
    union = np.logical_or.reduce(list(masks))
    h, w = (int(n) for n in union.shape)
    if not union.any():
        return (0, 0, w, h)
    ys, xs = np.flatnonzero(union.any(axis=1)), np.flatnonzero(union.any(axis=0))
    x_lo, x_hi, y_lo, y_hi = int(xs[0]), int(xs[-1]) + 1, int(ys[0]), int(ys[-1]) + 1
    cx, cy = (x_lo + x_hi) / 2, (y_lo + y_hi) / 2
    bw, bh = (x_hi - x_lo) * (1 + 2 * margin), (y_hi - y_lo) * (1 + 2 * margin)
    bw, bh = max(bw, bh * aspect), max(bh, bw / aspect)
    bw, bh = min(bw, w), min(bh, h)
    x0 = round(min(max(cx - bw / 2, 0.0), w - bw))
    y0 = round(min(max(cy - bh / 2, 0.0), h - bh))
    return (x0, y0, x0 + round(bw), y0 + round(bh))


def gif_frame_ms(fps: float) -> int:
    """GIF frame delay for ``fps``: GIF stores delays in whole centiseconds."""
    return 10 * max(2, round(100 / fps))  # browsers slow delays under 20 ms down to 100 ms


def make_gif(frames: Sequence[Image.Image], path: Path, *, width: int, fps: float, colors: int = 256) -> None:
    """Animated GIF, scaled to ``width``, all frames on one palette without dithering, looping forever."""
    from PIL import Image

    height = round(frames[0].height * width / frames[0].width)
    scaled = [f.convert("RGB").resize((width, height), Image.Resampling.LANCZOS) for f in frames]
    # One palette for all frames (taken from a strip of every frame): the floor keeps the same indices
    # in every frame, so GIF's frame differencing leaves only the robot to store.
    strip = Image.new("RGB", (width, scaled[0].height * len(scaled)))
    for i, f in enumerate(scaled):
        strip.paste(f, (0, i * f.height))
    # Octree keeps the rare saturated colours (the magenta TF line) and a smooth grey ramp on the head;
    # median cut turned the line purple and banded the head.
    palette = strip.quantize(colors=colors, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
    indexed = [f.quantize(palette=palette, dither=Image.Dither.NONE) for f in scaled]
    indexed[0].save(
        path,
        save_all=True,
        append_images=indexed[1:],
        duration=gif_frame_ms(fps),
        loop=0,
        optimize=True,
        disposal=1,
    )


# --------------------------------------------------------------------------------------------------
# The viewer


def check_prerequisites() -> str:
    """Path of the r2d2-viz CLI; raises SetupError naming everything that is missing."""
    reasons = viewers.missing_native_prerequisites()  # Xvfb, lavapipe ICD, libX11, the rerun CLI
    cli = Path(sys.executable).with_name("r2d2-viz")
    cli_path = str(cli) if cli.is_file() else shutil.which("r2d2-viz")
    if cli_path is None:
        reasons.append("r2d2-viz CLI not found next to the interpreter nor on PATH (pip install .)")
    for module, hint in (("PIL", "pip install pillow"), ("rerun.experimental", "pip install 'rerun-sdk>=0.41'")):
        try:
            __import__(module)
        except ImportError:
            reasons.append(f"python module {module!r} is missing ({hint})")
    if reasons:
        raise SetupError("cannot make screenshots here:\n  - " + "\n  - ".join(reasons))
    assert cli_path is not None
    return cli_path


def open_recording(client: ViewerClient, rrd: Path, timeout: float = 60.0) -> tuple[str, int]:
    """Open ``rrd``; wait for its ``time`` timeline. Returns (id of the 3D view, number of frames in the lap)."""
    client.open(str(rrd))
    deadline = time.monotonic() + timeout
    while True:
        state = client.get_state()
        recording = next((r for r in state.recordings if r.store_id == state.active_recording), None)
        timeline = None if recording is None else next((t for t in recording.timelines if t.name == TIMELINE), None)
        views_3d = [v.view_id for v in state.views if v.view_class == "3D"]
        if timeline is not None and len(views_3d) == 1:
            return views_3d[0], round(timeline.end * RATE_HZ / 1e9) + 1
        if time.monotonic() > deadline:
            raise TimeoutError(f"the viewer did not show {rrd} with one 3D view and a {TIMELINE!r} timeline: {state}")
        time.sleep(0.5)


def screenshot(client: ViewerClient, seconds: float, view_id: str | None = None) -> Image.Image:
    """What the viewer paints (whole window, or one view) with the time cursor paused at ``seconds``."""
    from PIL import Image

    client.set_time(TIMELINE, duration=seconds, play_state="paused")
    png = client.take_screenshot(view_id)  # blocks until the viewer has painted it
    image = Image.open(io.BytesIO(png))
    image.load()
    return image


# --------------------------------------------------------------------------------------------------


def make_screenshots(args: argparse.Namespace) -> list[Path]:
    cli = check_prerequisites()
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    window = (args.width, args.height)
    with tempfile.TemporaryDirectory(prefix="r2d2-screenshots-") as tmp_name:
        tmp = Path(tmp_name)
        rrd = tmp / "lap.rrd"
        subprocess.run([cli, "--save", str(rrd)], check=True, capture_output=True, timeout=300)
        print(f"recorded {rrd.name} ({rrd.stat().st_size / 1e6:.1f} MB)")
        log = tmp / "rerun.log"
        # The screen is larger than the window and the pointer is parked in its far corner (see viewers.xvfb),
        # so no hover tooltip ends up in a screenshot.
        with viewers.xvfb(window[0] + 200, window[1] + 200) as display:
            try:
                with viewers.native_viewer(display.display, window, log) as client:
                    view_3d, n_frames = open_recording(client, rrd)
                    print(f"viewer up, recording open ({n_frames} frames); waiting {args.settle:g} s for it to settle")
                    client.set_time(TIMELINE, duration=args.still_time, play_state="paused")
                    time.sleep(args.settle)  # the start-up notifications (software rasterizer, …) fade out
                    still = screenshot(client, args.still_time)
                    t0 = time.monotonic()
                    frames = [screenshot(client, t, view_3d) for t in lap_times(n_frames, args.frames)]
                    print(f"{len(frames)} frames of the 3D view in {time.monotonic() - t0:.0f} s")
            except Exception:
                print(f"viewer log (last lines):\n{viewers._tail(log)}", file=sys.stderr)
                raise

    still_path = out / STILL_NAME
    still.convert("RGB").save(still_path, optimize=True)
    arrays = [np.asarray(f.convert("RGB")) for f in frames]
    masks = [robot_mask(a) for a in arrays]
    if empty := [i for i, m in enumerate(masks) if m.sum() < 50]:
        raise RuntimeError(f"no robot in the 3D view in frames {empty}: is the recording right?")
    if same := [i for i in range(1, len(arrays)) if np.array_equal(arrays[i], arrays[i - 1])]:
        raise RuntimeError(f"frames {same} repeat the one before: the time cursor did not move")
    box = crop_box(masks)
    gif_path = out / GIF_NAME
    make_gif([f.crop(box) for f in frames], gif_path, width=args.gif_width, fps=args.fps)

    kb = still_path.stat().st_size / 1e3
    print(f"wrote {still_path} ({still.width}x{still.height}, {kb:.0f} kB; whole window at t = {args.still_time} s)")
    print(
        f"wrote {gif_path} ({args.gif_width} px wide, {len(frames)} frames, {gif_frame_ms(args.fps)} ms each, "
        f"{gif_path.stat().st_size / 1e3:.0f} kB; 3D view {frames[0].width}x{frames[0].height} cropped to {box})"
    )
    return [still_path, gif_path]


def make_bag_screenshot(
    cli: str, bag: Path, out: Path, *, seconds: float, window: tuple[int, int], settle: float
) -> Path:
    """``real-bag.png``: the whole window, ``seconds`` after the bag's first message, the time cursor paused."""
    with tempfile.TemporaryDirectory(prefix="r2d2-bag-screenshot-") as tmp_name:
        tmp = Path(tmp_name)
        rrd = tmp / "bag.rrd"
        subprocess.run([cli, "--bag", str(bag), "--save", str(rrd)], check=True, capture_output=True, timeout=600)
        log = tmp / "rerun.log"
        with viewers.xvfb(window[0] + 200, window[1] + 200) as display:
            try:
                with viewers.native_viewer(display.display, window, log) as client:
                    client.open(str(rrd))
                    deadline = time.monotonic() + 60
                    while True:
                        state = client.get_state()
                        recording = next((r for r in state.recordings if r.store_id == state.active_recording), None)
                        timeline = None
                        if recording is not None:
                            timeline = next((t for t in recording.timelines if t.name == TIMELINE), None)
                        if timeline is not None:
                            break
                        if time.monotonic() > deadline:
                            raise TimeoutError(f"the viewer did not show {rrd} with a {TIMELINE!r} timeline: {state}")
                        time.sleep(0.5)
                    at = timeline.start + round(seconds * 1e9)  # a bag's times are timestamps
                    client.set_time(TIMELINE, timestamp=np.datetime64(at, "ns"), play_state="paused")
                    time.sleep(settle)  # the start-up notifications fade out
                    png = client.take_screenshot()
            except Exception:
                print(f"viewer log (last lines):\n{viewers._tail(log)}", file=sys.stderr)
                raise
    from PIL import Image

    path = out / BAG_NAME
    Image.open(io.BytesIO(png)).convert("RGB").save(path, optimize=True)
    print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB; {bag.name} at {seconds:g} s after its first message)")
    return path


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--out", type=Path, default=REPO / "docs", help="directory for the images (default: docs)")
    parser.add_argument("--frames", type=int, default=144, help="frames of the lap in the GIF (default 144)")
    parser.add_argument("--fps", type=float, default=15.0, help="GIF frame rate (default 15)")
    parser.add_argument("--gif-width", type=int, default=640, help="GIF width in pixels (default 640)")
    parser.add_argument("--still-time", type=float, default=30.0, help="time of the still, seconds (default 30)")
    parser.add_argument("--width", type=int, default=1600, help="viewer window width (default 1600)")
    parser.add_argument("--height", type=int, default=1000, help="viewer window height (default 1000)")
    parser.add_argument("--settle", type=float, default=8.0, help="seconds to let start-up notifications fade")
    parser.add_argument("--bag", type=Path, default=None, help="also make real-bag.png from this ROS 2 bag")
    parser.add_argument("--bag-time", type=float, default=10.0, help="seconds into the bag for real-bag.png")
    parser.add_argument("--only-bag", action="store_true", help="make real-bag.png only (needs --bag)")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.frames < 2:
        print("error: --frames must be at least 2", file=sys.stderr)
        return 2
    t0 = time.monotonic()
    if args.only_bag and args.bag is None:
        print("error: --only-bag needs --bag", file=sys.stderr)
        return 2
    try:
        if not args.only_bag:
            make_screenshots(args)
        if args.bag is not None:
            cli = check_prerequisites()
            args.out.mkdir(parents=True, exist_ok=True)
            make_bag_screenshot(
                cli, args.bag, args.out, seconds=args.bag_time, window=(args.width, args.height), settle=args.settle
            )
    except SetupError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"done in {time.monotonic() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
