"""A ROS 2 bag replayed live into Rerun's web viewer: ``r2d2-viz --bag BAG --serve``, the R2D2 walking as the
bag's /joint_states and /tf say. The bag is written by rosbags (tests/bagmaker.py) from the line-by-line port
of the tutorial's state_publisher.py (tests/reference.py), with the URDF on /robot_description."""

from __future__ import annotations

from pathlib import Path

import pytest
from bagmaker import T0, BagSpec, joint_state, string, tf_message, write_bag
from reference import state_publisher

from .test_r2d2 import layout_problems, robot_problems, serve_in_browser

pytestmark = [pytest.mark.e2e, pytest.mark.slow]


def test_a_bag_replays_live_in_the_web_viewer(chromium_browser, artifacts_dir: Path, tutorial_urdf: Path) -> None:
    spec = BagSpec()
    spec.add("/robot_description", T0, string(tutorial_urdf.read_text()))
    for k, sample in enumerate(state_publisher(30 * 300)):  # five minutes at 30 Hz: time for the page to load
        t = T0 + round(k * 1e9 / 30)
        names, values = zip(*sample["joint_state"].items(), strict=True)  # type: ignore[attr-defined]
        spec.add("/joint_states", t, joint_state(t, names, values))
        spec.add("/tf", t, tf_message([(t, "odom", "axis", sample["odom_translation"], sample["odom_rotation_xyzw"])]))
    bag = write_bag(artifacts_dir / "tutorial_bag", spec, storage="sqlite3")
    img = serve_in_browser(chromium_browser, artifacts_dir, ["--bag", str(bag)], "web_bag")
    assert layout_problems(img) == [] and not any("white" in p for p in robot_problems(img))
