"""RViz's Decay Time in the real native viewer (Xvfb, lavapipe), checked from the pixels.

The bag (written by rosbags) has two lasers driving side by side along +x of ``odom`` at 0.35 m/s (/tf):
``laser_a`` at y = +1.5 m, ``laser_b`` at y = -1.5 m. Each publishes one scan a second, at T0 + k s for
k = 0..9 (the laser then at x = 0.35 k); scan k is a short arc (61 beams over ±0.15 rad, all 1 m) straight ahead,
at x = 1 + 0.35 k in ``odom``. The config (``--rviz``) draws /scan_a flat red with Decay Time 5 and /scan_b flat
green with none (RViz's default 0: only the latest scan), from straight above (TopDownOrtho: +x to the right of
the picture, +y up).

At 9.5 s, RViz keeps the scans received in the last 5 s (``PointCloudCommon``: dropped once now - received >
decay), k = 5..9, each where it was received: five red arcs side by side, the rightmost at x = 1 + 0.35 * 9;
one green arc, there too. Counted as runs of red (green) columns in the upper (lower) half of the 3D view. The
control: the same bag with Decay Time 0 on /scan_a must show one red arc. The viewer's own view reports must
hold no error.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from bagmaker import BagSpec, tf_message, write_bag
from conftest import cli
from msgs_build import T, cdr, header

from . import viewers

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

S = 1_000_000_000
T0 = 1_700_000_000 * S
SCANS = 10
SHOT_S = 9.5
DECAY_S = 5
WINDOW = (1600, 1000)
VIEW3D: viewers.Region = (0.14, 0.08, 0.62, 0.95)  # inside the 3D view (the side panel is the warnings log)


STEP = 0.35  # m a second


def _scan(frame: str, k: int) -> bytes:
    n = 61
    return cdr(
        T("sensor_msgs/msg/LaserScan")(
            header=header(frame, *divmod(T0 + k * S, S)),
            angle_min=-0.15,
            angle_max=0.15,
            angle_increment=0.3 / (n - 1),
            time_increment=0.0,
            scan_time=1.0,
            range_min=0.1,
            range_max=10.0,
            ranges=np.full(n, 1.0, dtype=np.float32),
            intensities=np.zeros(0, np.float32),
        )
    )


def write_decay_bag(path: Path) -> Path:
    types = {"/tf": "tf2_msgs/msg/TFMessage"}
    types |= {"/scan_a": "sensor_msgs/msg/LaserScan", "/scan_b": "sensor_msgs/msg/LaserScan"}
    spec = BagSpec(types=types)
    for k in range(SCANS):
        t = T0 + k * S
        lasers = [(t, "odom", "laser_a", (STEP * k, 1.5, 0.0), (0, 0, 0, 1))]
        lasers.append((t, "odom", "laser_b", (STEP * k, -1.5, 0.0), (0, 0, 0, 1)))
        spec.add("/tf", t, tf_message(lasers))
        spec.add("/scan_a", t + 1, _scan("laser_a", k))
        spec.add("/scan_b", t + 2, _scan("laser_b", k))
    spec.messages.sort(key=lambda m: m[1])
    return write_bag(path, spec, storage="mcap")


def config(decay_s: float) -> str:
    scan = (
        "    - {{Class: rviz_default_plugins/LaserScan, Name: {name}, Enabled: true, Topic: {{Value: {topic}}},"
        " Color Transformer: FlatColor, Color: '{color}', Size (m): 0.06{decay}}}\n"
    )
    return (
        "Visualization Manager:\n"
        "  Global Options: {Fixed Frame: odom, Background Color: '48; 48; 48'}\n"
        "  Displays:\n"
        "    - {Class: rviz_default_plugins/Grid, Enabled: false}\n"
        + scan.format(name="decayed", topic="/scan_a", color="255; 0; 0", decay=f", Decay Time: {decay_s}")
        + scan.format(name="latest", topic="/scan_b", color="0; 255; 0", decay="")
        + "  Views:\n    Current: {Class: rviz_default_plugins/TopDownOrtho, X: 2.6, Y: 0, Scale: 90, Angle: 0}\n"
    )


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("decay")
    bag = write_decay_bag(root / "bag")
    out = {}
    for case, decay in (("decay", DECAY_S), ("control", 0)):
        rviz = root / f"{case}.rviz"
        rviz.write_text(config(decay))
        rrd = root / f"{case}.rrd"
        run = cli("--bag", str(bag), "--rviz", str(rviz), "--save", str(rrd))
        assert run.returncode == 0, run.stderr
        out[case] = rrd
    return out


def runs(columns: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) of each run of True in a 1-D mask."""
    padded = np.concatenate([[False], columns, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def arcs(img: np.ndarray) -> dict[str, list[tuple[int, int]]]:
    """The column runs of red in the upper half and of green in the lower half of the 3D view."""
    rows, cols = viewers.region_slices(img.shape, VIEW3D)
    view = img[rows, cols].astype(np.int16)
    r, g, b = view[..., 0], view[..., 1], view[..., 2]
    half = view.shape[0] // 2
    red = (r > 150) & (g < 60) & (b < 60)
    green = (g > 150) & (r < 60) & (b < 60)
    return {"red": runs(red[:half].any(axis=0)), "green": runs(green[half:].any(axis=0))}


def shoot(rrd: Path, png: Path, log: Path, display: str) -> list[str]:
    """The native viewer at SHOT_S, paused: the screenshot, and the views' error reports."""
    with viewers.native_viewer(display, WINDOW, log) as client:
        client.open(str(rrd))
        deadline = time.monotonic() + 60
        while True:
            state = client.get_state()
            recording = next((r for r in state.recordings if r.store_id == state.active_recording), None)
            if recording is not None and any(t.name == "time" for t in recording.timelines):
                break
            assert time.monotonic() < deadline, f"no 'time' timeline: {state}"
            time.sleep(0.5)
        client.set_time("time", timestamp=np.datetime64(T0 + round(SHOT_S * S), "ns"), play_state="paused")
        viewers.still_screenshot(client, png)
        return [r.summary for v in client.get_state().views for r in v.reports if r.severity == "error"]


@pytest.mark.parametrize("case", ["decay", "control"])
def test_decay_time_keeps_the_last_seconds_of_scans(
    case: str, recordings: dict[str, Path], x_display, artifacts_dir: Path
) -> None:
    png = artifacts_dir / f"decay_{case}.png"
    reports = shoot(recordings[case], png, artifacts_dir / f"decay_{case}.log", x_display.display)
    found = arcs(viewers.load_png(png))
    print(f"{case}: {png}: {found}")
    assert reports == [], reports
    assert len(found["green"]) == 1, found  # /scan_b, no decay: the latest scan only
    red = found["red"]
    if case == "control":
        assert len(red) == 1, found
        return
    assert len(red) == 5, found  # k = 5..9: received in the last 5 s before 9.5 s
    # the newest red arc is scan 9, level with the green one (the lasers drive side by side); the red arcs step
    # evenly (0.35 m apart, where the laser was at each scan), so they are scans 5..9
    centres = [(a + b) / 2 for a, b in red]
    green = sum(found["green"][0]) / 2
    steps = np.diff(centres)
    assert abs(centres[-1] - green) < 0.25 * steps.mean(), (centres, green)
    assert steps.min() > 0.7 * steps.mean() and steps.max() < 1.3 * steps.mean(), centres
