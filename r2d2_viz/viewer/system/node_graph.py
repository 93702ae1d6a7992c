"""The graph of nodes and topics in a live recording (``--ros --tf-tree`` with a sink): ``/node_graph`` holds Rerun
``GraphNodes`` (a vertex per ROS node, blue, and per topic, grey) and ``GraphEdges`` (publisher → topic →
subscriber), logged whenever the graph changes, at that time: a node that left is gone from the snapshot logged
when it left, so scrubbing the timeline shows the graph as it was. :class:`NodeGraphLog` compares snapshots
(:meth:`~NodeGraphLog.update`, testable with stand-in node lists); :meth:`~NodeGraphLog.watch` polls a live
graph's discovery (:class:`~r2d2_viz.sources.system.node_graph.NodeWatch`) on a thread of its own."""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable, Sequence

import numpy as np
import rerun as rr

from r2d2_viz.sources.base import Clock
from r2d2_viz.sources.live.dds import LiveGraph, Node
from r2d2_viz.sources.system.node_graph import Graph, NodeWatch, graph_parts, positions
from r2d2_viz.sources.system.topic_health import LiveHealth
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.columns import encoded, send, time_array
from r2d2_viz.viewer.system.health import log_health

ENTITY = "/node_graph"
NODE_COLOR, TOPIC_COLOR = 0x1E88E5FF, 0x90A4AEFF
POLL_SECONDS = 1.0
"""How often the watching thread reads discovery."""
ARRIVALS = 1_000_000
"""At most this many samples' (topic, time, bytes) wait for the thread (a second at 1 MHz)."""
LATE_NS = 1_000_000_000
"""Health samples are logged up to this long before now: a sample's writer stamped it before it reached us."""


class NodeGraphLog:
    """Logs the node graph each time it differs from the last one logged."""

    def __init__(self, rec: rr.RecordingStream, *, clock: Clock, timeline: str = entities.TIMELINE) -> None:
        self.rec, self.clock, self.timeline = rec, clock, timeline
        self.last: Graph = graph_parts([])
        """The graph last logged (at first, the empty one: nothing is logged until a node is seen)."""
        self.snapshots = 0
        self.health_samples = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def update(self, time_ns: int, nodes: Sequence[Node]) -> bool:
        """The graph of ``nodes`` at ``time_ns``: logged if it changed (True)."""
        graph = graph_parts(nodes)
        if graph == self.last:
            return False
        self.last = graph
        n, m = len(graph.ids), len(graph.edges)
        colors = np.array([NODE_COLOR if is_node else TOPIC_COLOR for is_node in graph.is_node], np.uint32)
        columns = [
            *rr.GraphNodes.columns(
                node_ids=list(graph.ids), labels=list(graph.labels), colors=colors, positions=positions(graph)
            ).partition([n]),
            *rr.GraphEdges.columns(edges=list(graph.edges), graph_type=["directed"] * m).partition([m]),
            *rr.GraphNodes.columns(show_labels=[True]),
        ]
        send(self.rec, ENTITY, self.timeline, time_array(np.array([time_ns], np.int64), self.clock), encoded(columns))
        self.snapshots += 1
        return True

    def watch(
        self, source: object, *, period: float = POLL_SECONDS, wall_ns: Callable[[], int] = time.time_ns
    ) -> NodeGraphLog:
        """Poll the discovery of ``source``'s graph every ``period`` s until :meth:`stop` (nothing when it is not
        a live :class:`LiveGraph`, as in tests with stand-in graphs); each change logged at ``wall_ns()`` (the clock
        of the writers' source timestamps, the live run's timeline). The source's arrivals become each topic's
        health series (``/health/<topic>/rate`` and ``bandwidth``), sampled up to a second before ``wall_ns()``."""
        graph = getattr(source, "graph", None)
        if isinstance(graph, LiveGraph):
            arrivals: deque[tuple[str, int, int]] = deque(maxlen=ARRIVALS)
            source.arrivals = arrivals  # type: ignore[attr-defined]  # a LiveSource
            watch = NodeWatch(graph)
            args = (watch, arrivals, period, wall_ns)
            self._thread = threading.Thread(target=self._loop, args=args, daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        """Stop watching, after one last look."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None

    def _loop(
        self, watch: NodeWatch, arrivals: deque[tuple[str, int, int]], period: float, wall_ns: Callable[[], int]
    ) -> None:
        topics = LiveHealth()
        while True:
            stopping = self._stop.wait(period)
            try:
                now = wall_ns()
                self.update(now, watch.poll())
                got = [arrivals.popleft() for _ in range(len(arrivals))]
                self.health_samples += log_health(self.rec, topics.add(got, now - LATE_NS), self.clock)
            except Exception:  # the run is ending (the recording or the graph closed): nothing more to log
                return
            if stopping:
                return
