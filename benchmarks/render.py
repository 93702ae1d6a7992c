"""``--render`` speed (issue 45): frames per second that Rerun's headless viewer draws and PyAV encodes, on this
machine (no GPU here: Mesa's lavapipe), at two sizes, on tests/renderbags.py's 60 s R2D2 bag (still, moving, still).

For each size, alternating, ``rounds`` times (medians reported): ``r2d2-viz --bag B --render out.mp4 --fps 1
--size WxH --duration D`` for a long run (D seconds: D frames) and a one-frame run (D = 0.5 s). The one-frame run is
the fixed cost (recording the bag, starting the viewer twice, the start-up toasts fading); frames per second are
given both overall (frames / wall) and per frame once started ((long − one) / (frames − 1)). Outputs deleted first.

``--smoke`` (CI): 10 frames at one small size, one round, no verdicts.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from renderbags import write_render_bag  # noqa: E402


def r2d2_viz() -> list[str]:
    exe = Path(sys.executable).parent / "r2d2-viz"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "r2d2_viz"]


def timed_render(bag: Path, out: Path, size: str, seconds: float) -> float:
    """Wall seconds of one ``--render`` run (its output deleted first)."""
    out.unlink(missing_ok=True)
    command = [*r2d2_viz(), "--bag", str(bag), "--render", str(out), "--fps", "1", "--size", size]
    start = time.perf_counter()
    result = subprocess.run([*command, "--duration", f"{seconds:g}"], capture_output=True, text=True, timeout=1800)
    wall = time.perf_counter() - start
    if result.returncode != 0:
        raise SystemExit(f"render failed: {result.stderr.strip()}")
    return wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="10 frames at 320x180, one round (CI)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--frames", type=int, default=30, help="frames of the long run (1 fps: seconds of the bag)")
    args = parser.parse_args()
    sizes = ["320x180"] if args.smoke else ["640x360", "1280x720"]
    rounds, frames = (1, 10) if args.smoke else (args.rounds, args.frames)
    with tempfile.TemporaryDirectory(prefix="bench-render-") as tmp:
        bag = write_render_bag(Path(tmp) / "moving")
        walls: dict[tuple[str, int], list[float]] = {}
        for _ in range(rounds):
            for size in sizes:  # alternating sizes and lengths, so a busy spell of the machine hits them alike
                for n in (frames, 1):
                    wall = timed_render(bag, Path(tmp) / f"out-{size}.mp4", size, n if n > 1 else 0.5)
                    walls.setdefault((size, n), []).append(wall)
        print(f"--render, {frames} frames at 1 fps vs one frame, median of {rounds} (wall s)")
        print(f"{'size':>10} {'one frame':>10} {f'{frames} frames':>10} {'frames/s':>9} {'started':>9}")
        for size in sizes:
            one, long = statistics.median(walls[(size, 1)]), statistics.median(walls[(size, frames)])
            started = (frames - 1) / max(long - one, 1e-9)
            print(f"{size:>10} {one:>10.1f} {long:>10.1f} {frames / long:>9.2f} {started:>9.2f}")


if __name__ == "__main__":
    main()
