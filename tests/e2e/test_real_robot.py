"""A real humanoid in the native viewer: example-robot-data's TALOS (a 1.8 m humanoid with 32 joints and mesh
visuals), recorded with the defaults, fills at least 3 % of the 3D view — measured as the pixels that change
when the same recording is made without its visuals (same camera: the fit does not depend on mesh sizes)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from . import viewers
from .test_r2d2 import native_shot

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

VIEW3D = (0.13, 0.07, 0.70, 0.96)


def _talos() -> Path:
    from importlib import metadata

    robots = metadata.distribution("example-robot-data").locate_file("cmeel.prefix/share/example-robot-data/robots")
    return Path(str(robots)) / "talos_data" / "robots" / "talos_full_v2.urdf"


def test_a_humanoid_fills_the_view(x_display, artifacts_dir: Path) -> None:
    urdf = _talos()
    bare = artifacts_dir / "talos_without_visuals.urdf"
    bare.write_text(re.sub(r"<visual>.*?</visual>", "", urdf.read_text(), flags=re.S))
    shots = {}
    for name, description in (("talos", urdf), ("bare", bare)):
        rrd = artifacts_dir / f"{name}.rrd"
        exe = Path(sys.executable).parent / "r2d2-viz"
        subprocess.run(
            [str(exe), "--urdf", str(description), "--save", str(rrd), "--duration", "8"],
            check=True,
            capture_output=True,
            timeout=120,
        )
        png = artifacts_dir / f"{name}.png"
        # judged after the full 8 s: Talos's meshes may still be on their way to the GPU when two frames are alike
        log = artifacts_dir / f"{name}.log"
        native_shot(x_display.display, rrd, png, log, at=6.0, window=(1600, 1000), settled=lambda img, previous: False)
        shots[name] = viewers.load_png(png)
    region = viewers.region_slices(shots["talos"].shape, VIEW3D)
    robot = np.abs(shots["talos"][region].astype(int) - shots["bare"][region].astype(int)).max(-1) > 30
    assert robot.mean() >= 0.03, f"the humanoid covers {robot.mean():.1%} of the 3D view"
