"""Frame names as numbers, held to numpy's own ``np.unique`` of the fixed-width array; and the memory a long frame
name costs the tree's analysis (one 10,000-character name among the rows: issue 44 saw the run reach gigabytes)."""

from __future__ import annotations

import tracemalloc

import numpy as np
from tfbags import MS, T0, tf_message

from r2d2_viz.sources.live.dds import Sample
from r2d2_viz.sources.system.frame_codes import frame_codes
from r2d2_viz.sources.system.tf_live import samples_tree
from r2d2_viz.sources.system.tf_tree import analyse, tf_rows


def test_the_same_as_numpys_unique() -> None:
    rng = np.random.default_rng(7)
    pool = ["map", "odom", "base_link", "é/ünï", "", "a" * 300, "map2", "Map", "\x1b[31m", "z"]
    names = np.array([pool[i] for i in rng.integers(0, len(pool), 5_000)], dtype=object)
    distinct, codes = frame_codes(names)
    reference, inverse = np.unique(names.astype(str), return_inverse=True)
    assert distinct.tolist() == reference.tolist() and codes.tolist() == inverse.ravel().tolist()
    assert distinct.dtype == object and distinct[codes].tolist() == names.tolist()
    empty, none = frame_codes(np.zeros(0, object))
    assert len(empty) == 0 and len(none) == 0


def test_a_long_frame_name_costs_its_own_length_not_every_rows() -> None:
    # 2,000 rows, one of them to a 10,000-character child: a fixed-width copy of the 4,000 names is 4,000 cells of
    # 40 kB (UCS-4): 160 MB, then sorted (another copy); by hand, the rows' own arrays are well under 1 MB
    n = 2_000
    parents = ["map"] * n
    children = ["odom"] * (n - 1) + ["x" * 10_000]
    times = np.arange(n, dtype=np.int64) * 10_000_000
    rows = tf_rows(parents, children, times, times)
    tracemalloc.start()
    try:
        tree = analyse(rows, [("odom", "base_link")])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert {(e.parent, e.child) for e in tree.edges} == {("map", "odom"), ("map", "x" * 10_000), ("odom", "base_link")}
    assert peak < 5_000_000, peak


def test_the_live_tree_of_a_long_frame_name() -> None:
    # --ros --tf-tree: 40 /tf messages of 50 transforms, one each to a 10,000-character child (2,000 rows, as a
    # peer publishing it would send them; measured on a real DDS peer with 500 transforms a message over 4 s: the
    # CLI's peak went from 6.25 GB to 136 MB)
    q, long = (0.0, 0.0, 0.0, 1.0), "x" * 10_000
    samples = []
    for k in range(40):
        t = T0 + k * 100 * MS
        items = [(t, "odom", f"l{i}", (0.0, 0.0, 0.0), q) for i in range(49)] + [(t, "odom", long, (0.0, 0.0, 0.0), q)]
        samples.append(Sample("/tf", "tf2_msgs/msg/TFMessage", t, tf_message(items)))
    tracemalloc.start()
    try:
        tree = samples_tree(samples, (T0, T0 + 4000 * MS))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(tree.edges) == 50 and ("odom", long) in {(e.parent, e.child) for e in tree.edges}
    assert peak < 10_000_000, peak  # by hand: the rows and 40 messages of ~12 kB; a fixed-width copy is 160 MB
