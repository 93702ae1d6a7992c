"""Join a live ROS 2 graph with Cyclone DDS and read any message type as the raw CDR bytes a bag would hold.

Raw bytes: cyclonedds-python's sertype keeps every sample serialized (4-byte encapsulation header + body), and
its public ``DataReader.take`` hands each to the topic type's ``deserialize`` classmethod — which the types of
:meth:`~r2d2_viz.sources.live.idl_types.IdlTypes.raw_struct` define to keep the bytes. The topic type is still
built from rosbags' definitions because Cyclone validates incoming CDR against it.

QoS per topic, from what its writers offer (the built-in DCPSPublication topic): when a writer is reliable and
transient-local (``/tf_static``, ``/robot_description``, ``/map``) the reader is reliable + transient-local with a
deep history, so the latched samples of several publishers all arrive; otherwise it is best-effort + volatile,
which matches every writer, sensor-data ones included. Written: only what :meth:`LiveGraph.publish` is given (the
web page's tools: reliable, volatile, depth 1, as RViz's tools publish).

A drain thread moves samples from the readers into a bounded queue per topic (oldest dropped and counted);
:meth:`LiveGraph.poll` never blocks.
"""

from __future__ import annotations

import ctypes
import importlib
import os
import socket
import threading
import time
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from types import ModuleType, TracebackType
from typing import Any, NamedTuple

from r2d2_viz.errors import DEBUG_ENV, short
from r2d2_viz.msgs.typestore import MsgError, typestore
from r2d2_viz.sources.live.idl_types import IdlTypes, RawSample
from r2d2_viz.sources.live.names import LiveError, RosDiscovery, dds_topic, ros_topic, ros_type
from r2d2_viz.sources.live.writers import Writers

LATCHED_BY_NAME = frozenset({"/tf_static", "/robot_description", "/map", "/map_metadata", "/semantic_description"})
"""Topics taken as transient-local when no writer has been seen yet to tell."""
READER_DEPTH = 256
"""History of a volatile reader: the drain thread empties it within milliseconds, the queue holds the rest."""


class Sample(NamedTuple):
    """One received message: ROS topic, ROS type, the writer's source timestamp (ns), CDR bytes with header."""

    topic: str
    ros_type: str
    source_timestamp_ns: int
    data: bytes


@dataclass(frozen=True)
class Publication:
    """One DDS writer of a ROS 2 topic, as discovery announced it."""

    topic: str
    ros_type: str
    reliable: bool
    transient_local: bool


class Node(NamedTuple):
    """A ROS 2 node: its full name (``/namespace/name``) and the ``(topic, type)`` it publishes and subscribes."""

    name: str
    publishes: tuple[tuple[str, str], ...]
    subscribes: tuple[tuple[str, str], ...]


DISCOVERY, DISCOVERY_TYPE = "ros_discovery_info", "rmw_dds_common/msg/ParticipantEntitiesInfo"
READER_AFTER = 3.5
"""Seconds :meth:`LiveGraph.nodes` reads ``ros_discovery_info`` for once its reader exists: Fast DDS sends a late
reader the latched samples on its next heartbeat (every 3 s by default)."""


def cyclonedds_modules() -> dict[str, ModuleType]:
    """cyclonedds' modules, imported on first use (Cyclone's own log lines off: :func:`quiet_cyclone`); LiveError
    naming ``pip install cyclonedds`` if missing."""
    names = ("core", "domain", "topic", "sub", "pub", "builtin", "idl", "idl.types", "util")
    try:
        modules = {name: importlib.import_module(f"cyclonedds.{name}") for name in names}
    except ImportError as exc:
        raise LiveError(f"--ros needs Cyclone DDS for Python: pip install 'cyclonedds>=11,<12' ({exc})") from None
    quiet_cyclone()
    return modules


def quiet_cyclone() -> None:
    """Cyclone's own log lines off, unless ``R2D2_VIZ_DEBUG`` is set (as Rerun's are): the C library prints its
    warnings to the process's stderr (``1795867552.750 [0] dq.builtin: type [...]: ddsi_xt_type_init_impl with
    invalid type object`` for a Kilted peer), whatever ``CYCLONEDDS_URI``'s Tracing says; its log mask (fatal,
    error and warning by default) is set to none. Our own lines say what went wrong."""
    if os.environ.get(DEBUG_ENV):
        return
    from cyclonedds.internal import load_cyclonedds  # the library cyclonedds loaded (dlopen: the same one)

    library = load_cyclonedds()
    if library is not None:  # None: CYCLONEDDS_PYTHON_NO_IMPORT_LIBS
        library.dds_set_log_mask(ctypes.c_uint32(0))


def _publication(sample: Any, dds: Mapping[str, ModuleType]) -> Publication | None:
    topic, rtype = ros_topic(sample.topic_name), ros_type(sample.type_name)
    if topic is None or rtype is None:
        return None
    policy = dds["core"].Policy
    qos = sample.qos
    reliable = isinstance(qos[policy.Reliability], policy.Reliability.Reliable)
    durability = qos[policy.Durability]
    transient_local = durability is not None and durability != policy.Durability.Volatile
    # (an absent policy is the default, volatile; transient and persistent writers also serve late joiners)
    return Publication(topic, rtype, reliable, transient_local)


def resolvable(peers: tuple[str, ...], uri: str = "") -> None:
    """LiveError for a static peer Cyclone cannot resolve: it aborts the whole process on one (``add_peer_address:
    …: unknown address``, then SIGABRT), an IPv6 address included when it runs on IPv4 (its default, unless
    ``CYCLONEDDS_URI`` asks for udp6)."""
    family = socket.AF_UNSPEC if "udp6" in uri else socket.AF_INET
    for peer in peers:
        try:
            socket.getaddrinfo(peer, None, family)
        except (OSError, UnicodeError):
            why = "an IPv4 address or a host name" if family == socket.AF_INET else "an address or a host name"
            raise LiveError(f"ROS_STATIC_PEERS: cannot resolve {short(peer)!r} ({why})") from None


class LiveGraph:
    """A DDS participant on the ROS 2 graph of ``env`` (default: this process's environment).

    ``queue`` bounds the samples kept per topic between two polls (older ones are dropped and counted in
    :attr:`dropped`); ``latched_depth`` is the reader history of transient-local topics (one per publisher).
    """

    def __init__(
        self,
        env: Mapping[str, str] | None = None,
        *,
        distro: str = "jazzy",
        queue: int = 2000,
        latched_depth: int = 100,
    ) -> None:
        self._dds = cyclonedds_modules()
        self.distro = distro
        self.discovery = RosDiscovery.from_env(env)
        config = self.discovery.cyclone_xml()
        uri = (os.environ if env is None else env).get("CYCLONEDDS_URI", "")
        resolvable(self.discovery.static_peers, uri)
        if uri:
            config += "," + uri
        try:
            self._domain = self._dds["domain"].Domain(self.discovery.domain_id, config)
            self._participant = self._dds["domain"].DomainParticipant(self.discovery.domain_id)
        except Exception as exc:
            why = f"{exc}; set {DEBUG_ENV}=1 for Cyclone's own lines (CYCLONEDDS_URI?)"
            raise LiveError(f"cannot join ROS 2 domain {self.discovery.domain_id}: {why}") from None
        builtin = self._dds["builtin"]
        self._publications = builtin.BuiltinDataReader(self._participant, builtin.BuiltinTopicDcpsPublication)
        core = self._dds["core"]
        self._alive = core.ReadCondition(
            self._publications, core.SampleState.Any | core.ViewState.Any | core.InstanceState.Alive
        )
        try:
            self._types = IdlTypes(typestore(distro), self._dds["idl"])
        except MsgError as exc:
            raise LiveError(str(exc)) from None
        self._writers = Writers(self._dds, self._participant, self._types)
        self._queue = queue
        self._latched_depth = latched_depth
        self._readers: dict[str, tuple[str, Any]] = {}
        self._queues: dict[str, deque[Sample]] = {}
        self.dropped: dict[str, int] = {}
        """Samples dropped per topic because the queue was full (oldest first)."""
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._arrived = threading.Event()
        self._waitset = core.WaitSet(self._participant)
        self._wake = core.GuardCondition(self._participant)
        self._waitset.attach(self._wake)
        self._thread = threading.Thread(target=self._drain_loop, name="r2d2-viz-dds", daemon=True)
        self._thread.start()

    def publications(self) -> list[Publication]:
        """The ROS 2 writers discovered so far (alive ones)."""
        found = []
        for sample in self._publications.read(N=4096, condition=self._alive):
            if getattr(sample, "topic_name", None) is None:
                continue
            pub = _publication(sample, self._dds)
            if pub is not None:
                found.append(pub)
        return found

    def topics(self, timeout: float = 2.0) -> list[tuple[str, str, int]]:
        """``(topic, type, publisher count)`` by topic, after ``timeout`` s of discovery (``ros2 topic list -t``)."""
        time.sleep(max(0.0, timeout))
        counts: dict[tuple[str, str], int] = {}
        for pub in self.publications():
            counts[(pub.topic, pub.ros_type)] = counts.get((pub.topic, pub.ros_type), 0) + 1
        return sorted((topic, rtype, n) for (topic, rtype), n in counts.items())

    def nodes(self, timeout: float = 4.0) -> list[Node]:
        """The ROS 2 nodes of the graph after ``timeout`` s of discovery (:func:`graph_nodes`)."""
        return graph_nodes(self, timeout)

    def subscribe(self, topic: str, ros_type: str, *, wait: float = 1.0) -> Publication:
        """Read ``topic`` (``pkg/msg/T``); waits up to ``wait`` s for a writer to learn its QoS. Returns the
        reader's choice as a :class:`Publication` (``reliable`` / ``transient_local`` of the reader)."""
        name = dds_topic(topic)
        if topic in self._readers:
            raise LiveError(f"{topic} is already subscribed")
        writers = self._writers_of(topic, wait)
        durable = any(w.reliable and w.transient_local for w in writers) if writers else topic in LATCHED_BY_NAME
        policy = self._dds["core"].Policy
        if durable:
            qos = self._dds["core"].Qos(
                policy.Reliability.Reliable(max_blocking_time=0),
                policy.Durability.TransientLocal,
                policy.History.KeepLast(self._latched_depth),
            )
        else:
            qos = self._dds["core"].Qos(
                policy.Reliability.BestEffort,
                policy.Durability.Volatile,
                policy.History.KeepLast(min(self._queue, READER_DEPTH)),
            )
        try:
            raw_type = self._types.raw_struct(ros_type)
            dds_topic_entity = self._dds["topic"].Topic(self._participant, name, raw_type)
            reader = self._dds["sub"].DataReader(self._participant, dds_topic_entity, qos=qos)
        except LiveError:
            raise
        except Exception as exc:
            raise LiveError(f"cannot subscribe to {topic} ({ros_type}): {exc}") from None
        core = self._dds["core"]
        condition = core.ReadCondition(reader, core.SampleState.NotRead | core.ViewState.Any | core.InstanceState.Any)
        with self._lock:
            self._readers[topic] = (ros_type, reader)
            self._queues[topic] = deque(maxlen=self._queue if not durable else max(self._queue, self._latched_depth))
            self.dropped[topic] = 0
        self._waitset.attach(condition)
        self._wake.set(True)
        return Publication(topic, ros_type, durable, durable)

    def publish(self, topic: str, ros_type: str, data: bytes) -> None:
        """Write one message (CDR with its header) on ``topic``, as RViz's tools do (:class:`.writers.Writers`)."""
        self._writers.publish(topic, ros_type, data)

    def wait(self, timeout: float) -> bool:
        """Block until samples have arrived since the last poll (True), or ``timeout`` seconds (False)."""
        arrived = self._arrived.wait(timeout)
        self._arrived.clear()
        return arrived

    def poll(self) -> list[Sample]:
        """Every sample received since the last poll, oldest first per topic; never blocks."""
        with self._lock:
            out: list[Sample] = []
            for q in self._queues.values():
                out.extend(q)
                q.clear()
            return out

    def close(self) -> None:
        """Stop the drain thread and leave the domain."""
        if self._stop.is_set():
            return
        self._stop.set()
        self._wake.set(True)
        self._thread.join(timeout=5)
        self._participant = None
        self._domain = None

    def __enter__(self) -> LiveGraph:
        return self

    def __exit__(self, *exc: object | TracebackType) -> None:
        self.close()

    def _writers_of(self, topic: str, wait: float) -> list[Publication]:
        deadline = time.monotonic() + max(0.0, wait)
        while True:
            writers = [p for p in self.publications() if p.topic == topic]
            if writers or time.monotonic() >= deadline:
                return writers
            time.sleep(0.02)

    def _drain_loop(self) -> None:
        while not self._stop.is_set():
            self._waitset.wait(200_000_000)
            self._wake.set(False)
            with self._lock:
                readers = list(self._readers.items())
            for topic, (rtype, reader) in readers:
                got = reader.take(1024)  # RawSample each (IdlTypes.raw_struct), or InvalidSample for a disposal
                samples = [
                    Sample(topic, rtype, s.sample_info.source_timestamp, s.data)
                    for s in got
                    if isinstance(s, RawSample)
                ]
                if not samples:
                    continue
                with self._lock:
                    q = self._queues[topic]
                    overflow = len(q) + len(samples) - (q.maxlen or 0)
                    if overflow > 0:
                        self.dropped[topic] += overflow
                    q.extend(samples)
                self._arrived.set()
            time.sleep(0.001)


def graph_nodes(graph: LiveGraph, timeout: float) -> list[Node]:
    """The ROS 2 nodes of the graph after ``timeout`` s of discovery, as ``ros2 node list`` / ``ros2 node info``
    see them: their names from ``ros_discovery_info`` (rmw_dds_common's ParticipantEntitiesInfo, which every
    ROS 2 participant publishes, latched), their topics from DDS discovery, matched by endpoint GUID."""
    dds = graph._dds
    policy = dds["core"].Policy
    qos = dds["core"].Qos(
        policy.Reliability.Reliable(max_blocking_time=0),
        policy.Durability.TransientLocal,
        policy.History.KeepLast(graph._latched_depth),
    )
    deadline = time.monotonic() + max(0.0, timeout)
    while time.monotonic() < deadline - READER_AFTER and not any(  # a reader made before the writers are
        getattr(p, "topic_name", None) == DISCOVERY  # known hears nothing from Fast DDS (seen with rclpy, Jazzy)
        for p in graph._publications.read(N=4096, condition=graph._alive)
    ):
        time.sleep(0.1)
    time.sleep(0.5)  # the other participants' writers, discovered with the first
    try:
        info = graph._types.raw_struct(DISCOVERY_TYPE)
        reader = dds["sub"].DataReader(
            graph._participant, dds["topic"].Topic(graph._participant, DISCOVERY, info), qos=qos
        )
        subscriptions = dds["builtin"].BuiltinDataReader(
            graph._participant, dds["builtin"].BuiltinTopicDcpsSubscription
        )
    except Exception as exc:
        raise LiveError(f"cannot read the graph's nodes ({DISCOVERY}): {exc}") from None
    samples: list[Any] = []
    deadline = max(deadline, time.monotonic() + READER_AFTER)
    while (left := deadline - time.monotonic()) > 0:  # late joiners hear the latched history on a heartbeat
        time.sleep(min(0.25, left))
        samples += reader.take(N=4096)
    endpoints: dict[bytes, tuple[str, str, bool]] = {}  # GUID → (topic, type, is a writer)
    for kind, builtin in ((True, graph._publications), (False, subscriptions)):
        for sample in builtin.read(N=4096, condition=graph._alive if kind else None):
            topic = ros_topic(getattr(sample, "topic_name", "") or "")
            rtype = ros_type(getattr(sample, "type_name", "") or "")
            if topic is not None and rtype is not None:
                endpoints[sample.key.bytes] = (topic, rtype, kind)
    latest: dict[tuple[str, str], Node] = {}
    store = typestore(graph.distro)
    for sample in samples:
        if not isinstance(sample, RawSample):
            continue
        try:
            message: Any = store.deserialize_cdr(sample.data, DISCOVERY_TYPE)
        except Exception:  # a participant of another distro (Humble's 24-byte gids): not ours to name
            continue
        for node in message.node_entities_info_seq:
            own = [endpoints[g] for g in (bytes(x.data[:16]) for x in node.writer_gid_seq) if g in endpoints]
            own += [endpoints[g] for g in (bytes(x.data[:16]) for x in node.reader_gid_seq) if g in endpoints]
            name = node.node_namespace.rstrip("/") + "/" + node.node_name
            latest[(node.node_namespace, node.node_name)] = Node(
                name,
                tuple(sorted({(t, r) for t, r, w in own if w})),
                tuple(sorted({(t, r) for t, r, w in own if not w})),
            )
    return sorted(latest.values())


LIST_SECONDS = 2.0
"""How long ``--ros --list`` lets discovery run…"""
NODE_SECONDS = 5.0
"""…and its nodes' names: Fast DDS sends a late reader the latched ``ros_discovery_info`` on its next heartbeat
(every 3 s by default), so waiting less finds a node started a moment before only sometimes."""


def list_topics(
    timeout: float = LIST_SECONDS, env: Mapping[str, str] | None = None
) -> tuple[list[tuple[str, str, int]], list[Node], RosDiscovery]:
    """``(topic, type, publisher count)`` of the ROS 2 graph, like ``ros2 topic list -t`` (``--ros --list``), its
    nodes (``ros2 node list`` and ``ros2 node info``), and where discovery looked."""
    with LiveGraph(env) as graph:
        nodes = graph.nodes(max(timeout, NODE_SECONDS))
        return graph.topics(0.0), nodes, graph.discovery
