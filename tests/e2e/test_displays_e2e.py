"""A bag's RViz display topics in the real Rerun viewers (native on Xvfb with lavapipe, web in headless Chromium),
checked from the pixels: each thing is drawn, and where it is drawn relative to the others is where the bag puts it.

The bag (written by rosbags, like ``tests/displaybags.py``) is made for the eye: a laser 0.2 m above ``base_link``
(``odom`` → ``base_link`` → ``laser`` on /tf and /tf_static), its LaserScan a dense arc 2 m ahead (+x, ±0.5 rad,
201 beams, coloured by intensity: cyan in RViz's rainbow), a MarkerArray with a 0.6 m pure-red cube at (0.9, 0)
(between the laser and its arc) and a 0.6 m pure-green sphere at (1.9, 1.8) (beyond the arc's far end), and an
8 m x 8 m OccupancyGrid (free: white in the map scheme) with a 1 m x 0.6 m occupied block (black) centred at
(1.5, -1.5) (this side of the arc). Everything is drawn from 0.5 s on; nothing moves or expires.

The app frames the scene with its orbit camera from the -y side (yaw 264.6°, the tutorial's): in the picture +x
runs to the right and +y away from the camera, up the screen. Hence the checks: the red cube is LEFT of the arc
and of the sphere; from top to bottom come the green sphere, the arc, the black block; the arc runs up the screen
(taller than wide); the block lies on the white map. The control is a recording of the same bag without /scan,
/markers and /map: every check must fail on it (in the native viewer; the web page is judged by the same checks).
(The native check also asks the viewer for its views' error reports at that time: there must be none.)
"""

from __future__ import annotations

import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from bagmaker import BagSpec, tf_message, write_bag
from conftest import made_once
from msgs_build import T, cdr, color, header, marker_msg, pose, quat, vec

from . import viewers

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

S = 1_000_000_000
T0 = 1_700_000_000 * S
END_S = 3.0
SHOT_S = 2.5  # seconds after T0: every display message is in
DISPLAY_TOPICS = {
    "/scan": "sensor_msgs/msg/LaserScan",
    "/markers": "visualization_msgs/msg/MarkerArray",
    "/map": "nav_msgs/msg/OccupancyGrid",
}
SIZE = 0.6
CUBE = (0.9, 0.0, SIZE / 2)  # between the laser and its arc
SPHERE = (1.9, 1.8, SIZE / 2)  # beyond the arc's far end
WINDOW = (1600, 1000)  # native: the PNG is 2x
WEB_VIEWPORT = (1600, 1000)
VIEW3D: viewers.Region = (0.14, 0.08, 0.69, 0.95)  # inside the 3D view of the RViz-like layout, both viewers


# --------------------------------------------------------------------------------------------------
# The bag


BEAMS = 201
INTENSITIES = np.array([0.0, 100.0] + [60.0] * (BEAMS - 2), dtype=np.float32)
"""RViz's rainbow over [0, 100] draws 60 cyan (value 1 - 0.6 = 0.4): the arc is cyan but for its first two beams
(red and magenta), a colour nothing else in the scene has."""


def _scan(t_ns: int) -> bytes:
    n = BEAMS
    return cdr(
        T("sensor_msgs/msg/LaserScan")(
            header=header("laser", *divmod(t_ns, S)),
            angle_min=-0.5,
            angle_max=0.5,
            angle_increment=1.0 / (n - 1),
            time_increment=0.0,
            scan_time=0.1,
            range_min=0.1,
            range_max=10.0,
            ranges=np.full(n, 2.0, dtype=np.float32),
            intensities=INTENSITIES,
        )
    )


def _marker(kind: int, key: int, at: tuple[float, float, float], rgb: tuple[float, float, float]):
    return marker_msg(
        kind,
        header=header("odom", *divmod(T0, S)),
        ns="shapes",
        id=key,
        pose=pose(*at, quat(0, 0, 0, 1)),
        scale=vec(SIZE, SIZE, SIZE),
        color=color(*rgb),
    )


def _markers() -> bytes:
    cube = _marker(1, 1, CUBE, (1.0, 0.0, 0.0))
    sphere = _marker(2, 2, SPHERE, (0.0, 1.0, 0.0))
    return cdr(T("visualization_msgs/msg/MarkerArray")(markers=[cube, sphere]))


def _map() -> bytes:
    resolution, size = 0.1, 80  # 8 m x 8 m from (-4, -4)
    cells = np.zeros((size, size), dtype=np.int8)  # row = y, column = x
    cells[22:28, 50:60] = 100  # x in [1.0, 2.0), y in [-1.8, -1.2): occupied, black, nearer than the arc
    info = T("nav_msgs/msg/MapMetaData")(
        map_load_time=T("builtin_interfaces/msg/Time")(sec=0, nanosec=0),
        resolution=resolution,
        width=size,
        height=size,
        origin=pose(-4.0, -4.0, 0.0),
    )
    return cdr(T("nav_msgs/msg/OccupancyGrid")(header=header("odom", *divmod(T0, S)), info=info, data=cells.ravel()))


def write_pixel_bag(path: Path, *, displays: bool = True) -> Path:
    """The bag above; without /scan, /markers and /map when ``displays`` is False (the control)."""
    spec = BagSpec(types={"/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage"})
    if displays:
        spec.types.update(DISPLAY_TOPICS)
    spec.add("/tf_static", T0, tf_message([(T0, "base_link", "laser", (0.0, 0.0, 0.2), (0, 0, 0, 1))]))
    for k in range(round(END_S * 10) + 1):
        t = T0 + k * S // 10
        spec.add("/tf", t, tf_message([(t, "odom", "base_link", (0.0, 0.0, 0.0), (0, 0, 0, 1))]))
        if displays and k >= 1:
            spec.add("/scan", t + 1, _scan(t))
    if displays:
        spec.add("/map", T0 + S // 10 + 2, _map())
        spec.add("/markers", T0 + S // 2, _markers())
    spec.messages.sort(key=lambda m: m[1])
    return write_bag(path, spec, storage="mcap")


def record(bag: Path, out: Path) -> Path:
    """``r2d2-viz --bag BAG --save OUT``: the real CLI."""
    exe = Path(sys.executable).parent / "r2d2-viz"
    subprocess.run([str(exe), "--bag", str(bag), "--save", str(out)], check=True, capture_output=True, timeout=120)
    return out


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    def make(root: Path) -> None:
        for name in ("displays", "control"):
            record(write_pixel_bag(root / f"{name}_bag", displays=name == "displays"), root / f"{name}.rrd")

    root = made_once(tmp_path_factory, "display_recordings", make)
    return {name: root / f"{name}.rrd" for name in ("displays", "control")}


# --------------------------------------------------------------------------------------------------
# Pixels


def masks(img: np.ndarray) -> dict[str, np.ndarray]:
    """Per thing, the pixels of its colour inside the 3D view (whole-image coordinates, False outside it).
    Shading darkens the solids' faces, so colours are classes, not exact values."""
    rgb = img[..., :3].astype(np.int16)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    inside = np.zeros(img.shape[:2], dtype=bool)
    inside[viewers.region_slices(img.shape, VIEW3D)] = True
    return {
        "cube": inside & (r > 90) & (g < 40) & (b < 40),  # red
        "sphere": inside & (g > 90) & (r < 40) & (b < 40),  # green
        "scan": inside & (g > 150) & (np.abs(g - b) < 25) & (r < 40),  # cyan
        "block": inside & (rgb.max(-1) < 16),  # black (the background is 48;48;48)
        "map": inside & (rgb.min(-1) > 200),  # white: the free cells
    }


def centroid(mask: np.ndarray) -> tuple[float, float]:
    ys, xs = np.nonzero(mask)
    return float(xs.mean()), float(ys.mean())


def problems(img: np.ndarray) -> tuple[list[str], dict[str, float]]:
    """Empty when every thing is drawn and placed as the module docstring says; the measured fractions."""
    found = masks(img)
    region = viewers.region_slices(img.shape, VIEW3D)
    view_pixels = img[region].shape[0] * img[region].shape[1]
    fractions = {name: float(m.sum()) / view_pixels for name, m in found.items()}
    minimum = {"cube": 0.003, "sphere": 0.003, "scan": 0.00005, "block": 0.002, "map": 0.05}
    out = [f"{name}: {fractions[name]:.3%} of the 3D view" for name in minimum if fractions[name] < minimum[name]]
    if out:
        return out, fractions
    c = {name: centroid(m) for name, m in found.items() if name != "map"}
    if not c["cube"][0] < c["scan"][0]:  # x = 0.9 m vs 1.9 m: left of the arc
        out.append(f"the cube should be left of the arc: x = {c['cube'][0]:.0f}, {c['scan'][0]:.0f}")
    if not c["sphere"][1] < c["scan"][1] < c["block"][1]:  # y = 1.8 m, 0, -1.5 m: far to near, top to bottom
        ys = ", ".join(f"{c[k][1]:.0f}" for k in ("sphere", "scan", "block"))
        out.append(f"top to bottom should be sphere, arc, block: y = {ys}")
    if not c["cube"][0] < c["sphere"][0]:  # x = 0.9 m vs 1.9 m
        out.append(f"the cube should be left of the sphere: x = {c['cube'][0]:.0f}, {c['sphere'][0]:.0f}")
    # the arc: a thin curve (not a blob) that runs up the screen, the way +y goes (its 1.9 m chord lies along y)
    ys, xs = np.nonzero(found["scan"])
    w, h = int(xs.max() - xs.min()) + 1, int(ys.max() - ys.min()) + 1
    if not (h > w and found["scan"].sum() < 0.25 * w * h):
        out.append(f"the arc should be a thin curve up the screen: {w} x {h} px, {found['scan'].sum()} px drawn")
    # the black block lies on the white map: white within 60 px either side of it (the map's texture is filtered:
    # its edges blur over a few dozen pixels)
    bx0, by0, bx1, by1 = viewers.color_bbox(img, (0, 0, 0), tol=16, region=VIEW3D)
    row = img[(by0 + by1) // 2, :, :3].min(-1)
    if not (row[max(bx0 - 60, 0) : bx0].max() > 200 and row[bx1 : bx1 + 60].max() > 200):
        out.append("the black block should lie on the white map: no white beside it")
    return out, fractions


def _assert_shot(png: Path, case: str) -> dict[str, float]:
    found, fractions = problems(viewers.load_png(png))
    print(f"{case}: {png}: " + ", ".join(f"{k} {v:.3%}" for k, v in fractions.items()) + f"; problems {found}")
    if case == "displays":
        assert found == [], f"{png}: {found}"
    else:  # the control: nothing of the displays is drawn, so every check fails
        assert {p.split(":")[0] for p in found} >= {"cube", "sphere", "scan", "block", "map"}, f"{png}: {found}"
    return fractions


# --------------------------------------------------------------------------------------------------
# The viewers


@pytest.mark.parametrize("case", ["displays", "control"])
def test_native_viewer(case: str, recordings: dict[str, Path], x_display, artifacts_dir: Path) -> None:
    png = artifacts_dir / f"native_{case}.png"
    log = artifacts_dir / f"native_{case}.log"
    with viewers.native_viewer(x_display.display, WINDOW, log) as client:
        client.open(str(recordings[case]))
        deadline = time.monotonic() + 60
        while True:
            state = client.get_state()
            recording = next((r for r in state.recordings if r.store_id == state.active_recording), None)
            timeline = None if recording is None else next((t for t in recording.timelines if t.name == "time"), None)
            if timeline is not None:
                break
            assert time.monotonic() < deadline, f"no 'time' timeline: {state}"
            time.sleep(0.5)
        assert timeline.time_type == "timestamp"  # a bag's receive times
        client.set_time("time", timestamp=np.datetime64(T0 + round(SHOT_S * S), "ns"), play_state="paused")
        viewers.still_screenshot(client, png)
        reports = [r.summary for v in client.get_state().views for r in v.reports if r.severity == "error"]
    _assert_shot(png, case)
    assert reports == [], f"the viewer reports errors at {SHOT_S} s: {reports[:5]}"


# the control in the native viewer only: the web page is judged by the same checks on the same regions (a page
# costs 12-30 s of SwiftShader on two cores)
@pytest.mark.parametrize("case", ["displays"])
def test_web_viewer(case: str, recordings: dict[str, Path], chromium_browser, artifacts_dir: Path) -> None:
    # The web page plays the recording once and stops on its last time (3 s: everything drawn); settled = stopped.
    shot = viewers.screenshot_web(
        recordings[case],
        artifacts_dir / f"web_{case}.png",
        browser=chromium_browser,
        viewport=WEB_VIEWPORT,
        source="http",
        timeout=120,
        log_dir=artifacts_dir,
    )
    print(f"web {case}: {shot.seconds:.1f} s, stages {shot.stages}")
    _assert_shot(shot.path, case)


def test_the_arc_is_where_the_scan_says() -> None:
    """The bag itself: 201 beams, all 2 m, from -0.5 to 0.5 rad (so the arc spans y = ±2 sin 0.5 = ±0.96 m)."""
    from rosbags.typesys import Stores, get_typestore

    msg = get_typestore(Stores.ROS2_HUMBLE).deserialize_cdr(_scan(T0), "sensor_msgs/msg/LaserScan")
    last = msg.angle_min + (len(msg.ranges) - 1) * msg.angle_increment
    assert math.isclose(last, msg.angle_max, abs_tol=1e-6) and set(msg.ranges.tolist()) == {2.0}
