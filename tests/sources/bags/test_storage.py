"""Blocks: messages over one buffer, selected by topic and put in time order (values worked out by hand)."""

from __future__ import annotations

import numpy as np

from r2d2_viz.sources.bags.storage import block_of, topic_tuple


def test_block_of_joins_bytes_once_and_sorts_by_time_keeping_file_order_of_ties() -> None:
    topics = topic_tuple(["/b", "/a", "/b"])
    assert topics == ("/a", "/b")
    block = block_of([(30, "/b", b"xyz"), (10, "/a", b"p"), (30, "/a", b"qq"), (20, "/b", b"")], topics)
    assert block.times_ns.tolist() == [10, 20, 30, 30]
    assert [(t, topic, bytes(d)) for t, topic, d in block.messages()] == [
        (10, "/a", b"p"),
        (20, "/b", b""),
        (30, "/b", b"xyz"),
        (30, "/a", b"qq"),
    ]
    assert block.nbytes == 6
    b_rows = block.rows("/b")
    assert b_rows.tolist() == [1, 2]
    only_b = block.take(b_rows)
    assert [bytes(d) for _, d in only_b.pairs()] == [b"", b"xyz"]
    assert len(block.rows("/missing")) == 0
    assert isinstance(block.topic_index, np.ndarray)
