"""The live graph of nodes and topics (rqt_graph's): which ROS 2 nodes there are and what each publishes and
subscribes, watched while a live run goes on (:class:`NodeWatch`), as a graph of node and topic vertices with
publisher → topic → subscriber edges (:func:`graph_parts`). Nodes come from ``ros_discovery_info`` (one latched
sample per participant: the full list of its nodes, sent again when it changes), their topics from DDS
discovery, matched by endpoint GUID (as :func:`~r2d2_viz.sources.live.dds.graph_nodes` does once for ``--list``);
a participant that left (no longer alive in DCPSParticipant) takes its nodes with it. Pure but for the DDS reads."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any, NamedTuple

from r2d2_viz.msgs.typestore import typestore
from r2d2_viz.sources.live.dds import DISCOVERY, DISCOVERY_TYPE, LiveGraph, Node
from r2d2_viz.sources.live.idl_types import RawSample
from r2d2_viz.sources.live.names import ros_topic, ros_type

DEBUG_TOPICS = frozenset({"/rosout", "/parameter_events"})
"""Left out of the graph, as rqt_graph's "Hide Debug" (on by default) leaves them out: every node has them."""


class Graph(NamedTuple):
    """Vertices (``node /name`` and ``topic /name`` ids, their labels, whether each is a node) and edges."""

    ids: tuple[str, ...]
    labels: tuple[str, ...]
    is_node: tuple[bool, ...]
    edges: tuple[tuple[str, str], ...]


def graph_parts(nodes: Sequence[Node], hidden: frozenset[str] = DEBUG_TOPICS) -> Graph:
    """rqt_graph's "Nodes/Topics (all)": a vertex per node and per topic some node has, an edge from each publisher
    to its topic and from the topic to each subscriber; ``hidden`` topics left out. Sorted, so equal graphs are
    equal tuples."""
    topics = sorted({t for n in nodes for t, _ in (*n.publishes, *n.subscribes)} - hidden)
    names = sorted({n.name for n in nodes})
    edges: set[tuple[str, str]] = set()
    for n in nodes:
        edges |= {(f"node {n.name}", f"topic {t}") for t, _ in n.publishes if t not in hidden}
        edges |= {(f"topic {t}", f"node {n.name}") for t, _ in n.subscribes if t not in hidden}
    ids = (*(f"node {n}" for n in names), *(f"topic {t}" for t in topics))
    return Graph(ids, (*names, *topics), (True,) * len(names) + (False,) * len(topics), tuple(sorted(edges)))


SPACING = (230.0, 50.0)
"""Across (layers) and down (within a layer), in the graph view's units."""


def positions(graph: Graph) -> list[tuple[float, float]]:
    """Left to right as rqt_graph (dot) draws it: each vertex one layer after the furthest vertex with an edge into
    it (publishers, then their topics, then the topics' subscribers…), by name within a layer. A cycle (a node
    subscribing to what it publishes) stops growing after as many rounds as there are vertices."""
    layer = dict.fromkeys(graph.ids, 0)
    for _ in graph.ids:
        grown = False
        for a, b in graph.edges:
            if layer[b] <= layer[a] and layer[a] + 1 < len(graph.ids):
                layer[b], grown = layer[a] + 1, True
        if not grown:
            break
    rows: dict[int, int] = {}
    out = []
    for vertex in graph.ids:
        row = rows[layer[vertex]] = rows.get(layer[vertex], -1) + 1
        out.append((layer[vertex] * SPACING[0], row * SPACING[1]))
    return out


def nodes_of(infos: Iterable[Any], endpoints: Mapping[bytes, tuple[str, str, bool]]) -> list[Node]:
    """The nodes of ``infos`` (ParticipantEntitiesInfo messages, deserialised) with their topics: each node's writer
    and reader GIDs (first 16 bytes: the DDS GUID) looked up in ``endpoints`` (GUID → topic, type, is a writer)."""
    found: dict[str, Node] = {}
    for info in infos:
        for node in info.node_entities_info_seq:
            gids = [bytes(x.data[:16]) for x in (*node.writer_gid_seq, *node.reader_gid_seq)]
            own = [endpoints[g] for g in gids if g in endpoints]
            name = node.node_namespace.rstrip("/") + "/" + node.node_name
            found[name] = Node(
                name,
                tuple(sorted({(t, r) for t, r, w in own if w})),
                tuple(sorted({(t, r) for t, r, w in own if not w})),
            )
    return sorted(found.values())


class NodeWatch:
    """The nodes of a :class:`LiveGraph`, read again at each :meth:`poll` (never blocks). The reader of
    ``ros_discovery_info`` is made once a writer of it is known (Fast DDS's writers send a reader made earlier
    nothing: seen with rclpy, Jazzy)."""

    def __init__(self, graph: LiveGraph) -> None:
        self.graph = graph
        dds = graph._dds
        core, builtin = dds["core"], dds["builtin"]
        self._subscriptions = builtin.BuiltinDataReader(graph._participant, builtin.BuiltinTopicDcpsSubscription)
        self._participants = builtin.BuiltinDataReader(graph._participant, builtin.BuiltinTopicDcpsParticipant)
        alive = core.SampleState.Any | core.ViewState.Any | core.InstanceState.Alive
        self._alive_subscriptions = core.ReadCondition(self._subscriptions, alive)
        self._alive_participants = core.ReadCondition(self._participants, alive)
        self._reader: Any = None
        self._latest: dict[bytes, Any] = {}  # participant GUID → its latest ParticipantEntitiesInfo
        self._store = typestore(graph.distro)

    def poll(self) -> list[Node]:
        """The nodes of the participants alive now, with their alive topics."""
        graph = self.graph
        publications = graph._publications.read(N=4096, condition=graph._alive)
        if self._reader is None and any(getattr(p, "topic_name", None) == DISCOVERY for p in publications):
            self._reader = self._make_reader()
        for sample in self._reader.take(N=4096) if self._reader is not None else ():
            if not isinstance(sample, RawSample):
                continue
            try:
                info: Any = self._store.deserialize_cdr(sample.data, DISCOVERY_TYPE)
            except Exception:  # a participant of another distro (Humble's 24-byte gids): not ours to name
                continue
            self._latest[bytes(info.gid.data[:16])] = info
        alive = {p.key.bytes for p in self._participants.read(N=4096, condition=self._alive_participants)}
        endpoints: dict[bytes, tuple[str, str, bool]] = {}
        subscriptions = self._subscriptions.read(N=4096, condition=self._alive_subscriptions)
        for is_writer, samples in ((True, publications), (False, subscriptions)):
            for s in samples:
                topic = ros_topic(getattr(s, "topic_name", "") or "")
                rtype = ros_type(getattr(s, "type_name", "") or "")
                if topic is not None and rtype is not None:
                    endpoints[s.key.bytes] = (topic, rtype, is_writer)
        return nodes_of((info for gid, info in self._latest.items() if gid in alive), endpoints)

    def _make_reader(self) -> Any:
        dds = self.graph._dds
        policy = dds["core"].Policy
        qos = dds["core"].Qos(
            policy.Reliability.Reliable(max_blocking_time=0),
            policy.Durability.TransientLocal,
            policy.History.KeepLast(self.graph._latched_depth),
        )
        info = self.graph._types.raw_struct(DISCOVERY_TYPE)
        topic = dds["topic"].Topic(self.graph._participant, DISCOVERY, info)
        return dds["sub"].DataReader(self.graph._participant, topic, qos=qos)
