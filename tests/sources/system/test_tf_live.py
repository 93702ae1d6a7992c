"""The TF tree of received DDS samples (their writers' source timestamps), as ``--ros --tf-tree`` builds it; the
live listening itself runs with a real rclpy node in tests/cli/test_system.py."""

from __future__ import annotations

from tfbags import MS, T0, tf_message

from r2d2_viz.sources.live.dds import Sample
from r2d2_viz.sources.system.tf_live import samples_tree

Q = (0.0, 0.0, 0.0, 1.0)
TF = "tf2_msgs/msg/TFMessage"


def test_samples_give_rates_statics_and_stale_frames() -> None:
    samples = [Sample("/tf_static", TF, T0, tf_message([(T0, "base_link", "laser", (0, 0, 0.1), Q)]))]
    for k in range(50):  # 5 s at 10 Hz
        t = T0 + k * 100 * MS
        items = [(t, "odom", "base_link", (k, 0, 0), Q)] + ([(t, "base_link", "wheel", (0, 0, 0), Q)] if k < 10 else [])
        samples.append(Sample("/tf", TF, t, tf_message(items)))
    tree = samples_tree(samples[::-1], (T0, T0 + 5000 * MS))  # arrival order does not matter
    edges = {(e.parent, e.child): e for e in tree.edges}
    assert edges["odom", "base_link"].rate_hz == 10.0 and edges["odom", "base_link"].count == 50
    assert edges["base_link", "laser"].static
    assert tree.problems == (
        "frame wheel: stale: its transform from base_link stopped 4.1 s before the end of listening "
        "(41 periods of its 10 Hz)",
    )
