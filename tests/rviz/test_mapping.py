"""docs/rviz.md's RViz table is the converter's own mapping, and the mapping names what the converter reads."""

from __future__ import annotations

from conftest import REPO

from r2d2_viz.rviz.mapping import MAPPING, mapping_markdown
from r2d2_viz.rviz.spec import TOPIC_DISPLAYS


def test_the_docs_table_is_the_mapping() -> None:
    assert mapping_markdown() in (REPO / "docs" / "rviz.md").read_text()


def test_every_topic_display_class_the_converter_reads_is_in_the_table() -> None:
    classes = {c.strip() for cls, _, _ in MAPPING for c in cls.split(",")}
    assert set(TOPIC_DISPLAYS) - {"PointCloud", "PointStamped"} <= classes
