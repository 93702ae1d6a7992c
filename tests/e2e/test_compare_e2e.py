"""``r2d2-viz --compare A B`` in the native viewer: the walking R2D2 of two bags (written by rosbags from the
line-by-line port of the tutorial's state_publisher.py, tests/reference.py), the second starting 0.7 s later with its
swivel 0.3 rad off and put 4 s ahead on the timeline (``--offset``) so the two stand apart on the circle: the first
robot drawn as it is (white), the second an orange ghost, and one plot holding the swivel of both. The screenshot
is docs/compare.png."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from bagmaker import T0, BagSpec, joint_state, string, tf_message, write_bag
from reference import state_publisher

from . import viewers
from .test_r2d2 import native_shot

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

VIEW3D = (0.0, 0.05, 0.66, 0.72)  # the 3D view: left two thirds, above the Differences view
PLOT = (0.67, 0.45, 1.0, 0.78)  # the --plot view: right third, second from the top


def _bag(path: Path, urdf: Path, *, late: bool) -> Path:
    spec = BagSpec()
    start = T0 + (700_000_000 if late else 0)
    spec.add("/robot_description", start, string(urdf.read_text()))
    for k, sample in enumerate(state_publisher(30 * 12)):
        t = start + round(k * 1e9 / 30)
        joints = dict(sample["joint_state"])  # type: ignore[call-overload]
        if late:
            joints["swivel"] += 0.3
        spec.add("/joint_states", t, joint_state(t, list(joints), list(joints.values())))
        spec.add("/tf", t, tf_message([(t, "odom", "axis", sample["odom_translation"], sample["odom_rotation_xyzw"])]))
    return write_bag(path, spec)


def test_two_robots_one_a_ghost_and_an_overlaid_plot(x_display, artifacts_dir: Path, tutorial_urdf: Path) -> None:
    a, b = (
        _bag(artifacts_dir / "monday", tutorial_urdf, late=False),
        _bag(artifacts_dir / "tuesday", tutorial_urdf, late=True),
    )
    rrd = artifacts_dir / "compare.rrd"
    exe = Path(sys.executable).parent / "r2d2-viz"
    args = [str(a), str(b), "--offset", "tuesday=-4", "--plot", "/joint_states.position[2]", "--save", str(rrd)]
    subprocess.run([str(exe), "--compare", *args], check=True, capture_output=True, timeout=300)
    png = artifacts_dir / "compare.png"
    native_shot(x_display.display, rrd, png, artifacts_dir / "compare.log", at=6.0, window=(1600, 1000))
    img = viewers.load_png(png).astype(int)
    r, g, bl = img[..., 0], img[..., 1], img[..., 2]
    orange = (r > 150) & (r - bl > 90) & (g > 60) & (g < r - 40)  # the ghost's tint (255, 140, 0), translucent
    light = (r > 170) & (g > 130) & (bl > 110) & (r - bl < 90)  # the first robot (white, shaded)
    view = viewers.region_slices(img.shape, VIEW3D)
    assert orange[view].mean() > 0.002 and light[view].mean() > 0.002, (orange[view].mean(), light[view].mean())
    # the plot: each run's series in its own colour (Rerun picks them: one yellow-green, one violet here)
    plot = viewers.region_slices(img.shape, PLOT)
    yellow = (r > 140) & (g > 140) & (bl < 110)
    violet = (bl > 150) & (bl > r + 30) & (bl > g + 60)
    assert yellow[plot].mean() > 0.001 and violet[plot].mean() > 0.001, (yellow[plot].mean(), violet[plot].mean())
