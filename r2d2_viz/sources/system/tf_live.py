"""The TF tree of a live graph: ``/tf`` and ``/tf_static`` listened to for some seconds through
:class:`~r2d2_viz.sources.live.dds.LiveGraph` (each message at its writer's source timestamp, the clock a bag's
receive times are on), then analysed like a bag's (:func:`~.tf_tree.analyse`). Pure; no rerun import."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from r2d2_viz.msgs.typestore import deserialize
from r2d2_viz.sources.bag_tf import TF_MESSAGE, TfDecoder
from r2d2_viz.sources.live.dds import LiveGraph, Sample
from r2d2_viz.sources.system.tf_tree import TfTree, analyse, tf_rows

SUBSCRIBE_WAIT = 1.0
"""Seconds each subscription waits for a writer (to learn whether /tf_static is latched)."""


def samples_tree(samples: Sequence[Sample], span_ns: tuple[int, int]) -> TfTree:
    """The tree of received ``/tf`` and ``/tf_static`` samples over ``span_ns`` (wall clock, ns)."""
    receive = TfDecoder(deserialize, static=False, time="receive")
    stamped = TfDecoder(deserialize, static=False, time="header")
    static = TfDecoder(deserialize, static=True, time="receive")
    moving = [(s.source_timestamp_ns, s.data) for s in samples if s.topic == "/tf"]
    latched = [(s.source_timestamp_ns, s.data) for s in samples if s.topic == "/tf_static"]
    a, b = receive.decode(moving), stamped.decode(moving)
    rows = tf_rows(a.parents, a.children, a.times_ns, b.times_ns)
    order = np.argsort(rows.receive_ns, kind="stable")
    rows = type(rows)(rows.parents[order], rows.children[order], rows.receive_ns[order], rows.stamps_ns[order])
    return analyse(rows, static.decode(latched).edges(), span_ns=span_ns, end_word="the end of listening")


def live_tree(
    seconds: float,
    env: Mapping[str, str] | None = None,
    *,
    clock: Callable[[], float] = time.monotonic,
    wall_ns: Callable[[], int] = time.time_ns,
) -> tuple[TfTree, str]:
    """Listen to ``/tf`` and ``/tf_static`` for ``seconds``; the tree and where discovery looked."""
    with LiveGraph(env) as graph:
        start = wall_ns()
        for topic in ("/tf_static", "/tf"):
            graph.subscribe(topic, TF_MESSAGE, wait=SUBSCRIBE_WAIT)
        samples: list[Sample] = []
        deadline = clock() + seconds
        while (left := deadline - clock()) > 0:
            graph.wait(min(0.2, left))
            samples += graph.poll()
        samples += graph.poll()
        return samples_tree(samples, (start, wall_ns())), graph.discovery.searched()
