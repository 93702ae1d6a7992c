"""The other topics' fields in a bag's one pass: which topics (all of them, or a --plot path's fields only), a
topic that cannot be decoded known before the pass, --plot paths checked before anything is read (bags written by
rosbags: tests/fieldbags.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
from fieldbags import BATTERY, messages, write

from r2d2_viz.errors import BagError
from r2d2_viz.sources.bags.bag import open_bag
from r2d2_viz.sources.fields_pass import FieldsPass, plot_paths
from r2d2_viz.sources.playback import BagPass, Segment


@pytest.fixture(scope="module")
def bag_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write(tmp_path_factory.mktemp("fields") / "bag", messages(50))


def test_the_pass_reads_the_fields_topics_in_its_last_segment(bag_path: Path) -> None:
    with open_bag(bag_path) as bag:
        start = bag.span[0] if bag.span else 0
        [plot] = plot_paths(bag, ["/odom.twist.twist.linear.x"])
        fields = FieldsPass(bag, {"/battery": BATTERY}, [plot])
        preroll, main = Segment(("/tf",), None, start + 100_000_000), Segment((), start + 100_000_000, None)
        bag_pass = BagPass(bag, [preroll, main], actuated=None, displays={}, fields=fields)
        assert bag_pass.segments[0] == preroll and set(bag_pass.segments[1].topics) == {"/battery", "/odom"}
        rows: dict[str, int] = {}
        for window in bag_pass.windows(1000, max_bytes=4096):  # many small windows
            for topic, columns in window.fields:
                rows[topic] = rows.get(topic, 0) + len(columns)
                if topic == "/odom":
                    assert set(columns.numbers) == {"twist.twist.linear.x"} and not columns.texts
    assert rows == {"/battery": 40, "/odom": 40}  # the last 40 of 50 messages at 100 Hz: after the first 100 ms


def test_plot_paths_name_the_fields_when_they_name_nothing(bag_path: Path) -> None:
    with open_bag(bag_path) as bag:
        with pytest.raises(BagError, match=r"^--plot /nope\.x: .* has no topic /nope \(its topics: /arm_controller"):
            plot_paths(bag, ["/nope.x"])
        with pytest.raises(BagError, match=r"has no field volts there; /battery's fields: header\.stamp\.sec, "):
            plot_paths(bag, ["/battery.volts"])
        with pytest.raises(BagError, match=r"^--plot /battery: not a message path"):
            plot_paths(bag, ["/battery"])
