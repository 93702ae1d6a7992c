"""A live ROS 2 graph as a source: what a :class:`~r2d2_viz.sources.live.dds.LiveGraph` receives, sorted for the
viewer the way a bag replay sorts a bag — joint states into :class:`~r2d2_viz.sources.base.SampleChunk` s (decoded
in bulk like a bag's), ``/tf`` and ``/tf_static`` into :class:`~r2d2_viz.sources.base.TfRecords`, display topics
into :class:`~r2d2_viz.sources.bag_displays.TopicMessage` s, ``/robot_description`` into URDF texts.

The graph is re-read every ``refresh`` seconds: topics that appear are subscribed (publishers may come, go and come
back — a reader stays and matches them again). Times are the writers' source timestamps, or header stamps
(``time="header"``). Problems (a wrong type, undecodable or inconsistent messages, samples dropped because the
viewer fell behind) become notes, each kind once per topic: ``(key, line)`` pairs for the viewer's Notices.
Pure: no rerun, no DDS import (the graph is handed in).
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Collection, Container, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from r2d2_viz.errors import listed
from r2d2_viz.msgs.registry import DECODERS
from r2d2_viz.msgs.typestore import MsgError, deserialize
from r2d2_viz.sources.bag_displays import OURS, TopicMessage
from r2d2_viz.sources.bag_joints import JOINT_STATE, STRING, JointStateDecoder, TimeSource
from r2d2_viz.sources.bag_tf import TF_MESSAGE, TfDecoder
from r2d2_viz.sources.base import SampleChunk, TfRecords
from r2d2_viz.sources.live.dds import Publication, Sample
from r2d2_viz.sources.live.names import LiveError
from r2d2_viz.sources.robots import SHARED_FRAMES, prefix_of, renamed

EXPECTED = {
    "/joint_states": JOINT_STATE,
    "/tf": TF_MESSAGE,
    "/tf_static": TF_MESSAGE,
    "/robot_description": STRING,
}
"""The robot pipeline's own topics and the one type each is read as (a publisher of another type is reported); the
same names in a namespace (``/robot2/joint_states``) are another robot's (:mod:`r2d2_viz.sources.robots`)."""


def robot_topic(topic: str) -> tuple[str, str] | None:
    """``/robot2/tf`` → ``("/robot2", "/tf")``; ``/tf`` → ``("", "/tf")``; None for other topics."""
    namespace, _, name = topic.rpartition("/")
    return (namespace, "/" + name) if "/" + name in EXPECTED else None


PENDING_JOINT_STATES = 1000
"""Joint states kept while no robot is known yet (the newest), decoded when its description arrives."""
MAX_DESCRIPTION_BYTES = 64 << 20
JOINT_PROBLEMS = {
    "skipped": "messages whose name and position lengths differ are skipped",
    "undecodable": "messages that cannot be decoded are skipped",
    "nonfinite": "NaN or infinite positions are ignored (the joint keeps its last value)",
}


class Graph(Protocol):
    """What of :class:`~r2d2_viz.sources.live.dds.LiveGraph` a source uses."""

    dropped: dict[str, int]

    def publications(self) -> list[Publication]: ...

    def subscribe(self, topic: str, ros_type: str, *, wait: float = 1.0) -> Publication: ...

    def poll(self) -> list[Sample]: ...

    def wait(self, timeout: float) -> bool: ...


@dataclass
class LiveBatch:
    """What arrived since the last poll, sorted."""

    samples: list[Sample] = field(default_factory=list)
    """Everything received, as it came (for ``--save out.mcap``)."""
    descriptions: list[str] = field(default_factory=list)
    joints: SampleChunk | None = None
    robot_descriptions: list[tuple[str, str]] = field(default_factory=list)
    """Namespaced robots: ``(namespace, URDF)`` from ``/<namespace>/robot_description``."""
    robot_joints: dict[str, SampleChunk] = field(default_factory=dict)
    """Namespaced robots: namespace → its ``/<namespace>/joint_states``."""
    tf: list[TfRecords] = field(default_factory=list)
    """Static records (``/tf_static``) before moving ones."""
    displays: list[TopicMessage] = field(default_factory=list)
    fields: list[TopicMessage] = field(default_factory=list)
    """Topics no display draws, of a type the graph's typestore knows (their fields are shown)."""
    notes: list[tuple[str, str]] = field(default_factory=list)
    """``(key, line)``: each key is worth saying once."""


def _deserialize(data: bytes | memoryview, msgtype: str) -> Any:
    return deserialize(bytes(data), msgtype)


class LiveSource:
    """Subscribes to ``topics`` (None: every displayable one, the robot's own) on ``graph``; sorts what arrives."""

    def __init__(
        self,
        graph: Graph,
        *,
        topics: Collection[str] | None = None,
        time: TimeSource = "receive",
        refresh: float = 1.0,
        shared_frames: Sequence[str] = SHARED_FRAMES,
        known_types: Container[str] = (),
    ) -> None:
        self.graph, self.time, self.refresh_period, self.known_types = graph, time, refresh, known_types  # (fields)
        self.wanted = None if topics is None else {*topics, *OURS}
        self.subscribed: dict[str, str] = {}
        self.received: dict[str, int] = {}
        self.arrivals: deque[tuple[str, int, int]] | None = None  # set: each sample's (topic, time, bytes) added
        self._refused: set[tuple[str, str]] = set()
        self._joints: JointStateDecoder | None = None
        self._pending: deque[tuple[int, bytes]] = deque(maxlen=PENDING_JOINT_STATES)
        self._tf = {t: TfDecoder(_deserialize, static=t == "/tf_static", time=time) for t in ("/tf", "/tf_static")}
        self._tf_nonfinite = {"/tf": 0, "/tf_static": 0}
        self._next_refresh, self.shared_frames = 0.0, tuple(shared_frames)
        self._robot_joints: dict[str, JointStateDecoder] = {}
        self._robot_pending: dict[str, deque[tuple[int, bytes]]] = {}
        self._dropped: dict[str, int] = {}
        self._notes: list[tuple[str, str]] = []
        self._said_joint_problems: set[str] = set()

    # --- the graph -------------------------------------------------------------------------------

    def refresh(self, now: float | None = None) -> None:
        """Subscribe to the wanted topics that have appeared (at most once per ``refresh`` seconds)."""
        now = time.monotonic() if now is None else now
        if now < self._next_refresh:
            return
        self._next_refresh = now + self.refresh_period
        for pub in self.graph.publications():
            topic, rtype = pub.topic, pub.ros_type
            if topic in self.subscribed or (topic, rtype) in self._refused:
                continue
            ours = robot_topic(topic)
            expected = EXPECTED[ours[1]] if ours is not None else None
            shown = rtype in DECODERS or rtype in self.known_types
            if expected is None and self.wanted is None and not shown:
                continue  # a topic nothing can show
            if self.wanted is not None and topic not in self.wanted and ours is None:
                continue
            if (expected is not None and rtype != expected) or (expected is None and not shown):
                self._refused.add((topic, rtype))
                want = expected or "a type a display draws"
                self._note(f"type {topic} {rtype}", f"{topic}: a publisher of {rtype}, not {want}: not read")
                continue
            try:
                self.graph.subscribe(topic, rtype, wait=0.0)
            except LiveError as exc:
                self._refused.add((topic, rtype))
                self._note(f"subscribe {topic}", f"{topic}: not read: {exc}")
                continue
            self.subscribed[topic] = rtype

    @property
    def display_topics(self) -> dict[str, str]:
        """The display topics subscribed to so far (topic → type): the robot pipeline's own left out."""
        return {topic: rtype for topic, rtype in self.subscribed.items() if robot_topic(topic) is None}

    def set_joints(self, actuated: Sequence[str] | None, namespace: str = "") -> None:
        """The robot's actuated joints (a new description), or None: no robot, joint states are kept for later;
        ``namespace``: another robot's (``/robot2``)."""
        if namespace:
            self._robot_joints.pop(namespace, None)
            if actuated is not None:
                decoder = JointStateDecoder(actuated, time=self.time, deserialize=_deserialize)
                self._robot_joints[namespace] = decoder
            return
        self._joints = None
        if actuated is not None:
            self._joints = JointStateDecoder(actuated, time=self.time, deserialize=_deserialize)
        self._said_joint_problems.clear()

    # --- samples ---------------------------------------------------------------------------------

    def poll(self, now: float | None = None) -> LiveBatch:
        """Refresh the subscriptions when due, then everything received since the last poll; never blocks."""
        self.refresh(now)
        batch = LiveBatch(samples=self.graph.poll())
        tf: dict[str, list[tuple[int, bytes]]] = {"/tf_static": [], "/tf": []}
        joints: list[tuple[int, bytes]] = []
        robot_joints: dict[str, list[tuple[int, bytes]]] = {}
        for s in batch.samples:
            self.received[s.topic] = self.received.get(s.topic, 0) + 1
            if self.arrivals is not None:
                self.arrivals.append((s.topic, s.source_timestamp_ns, len(s.data)))
            namespace, name = robot_topic(s.topic) or ("", "")
            if s.topic == "/joint_states":
                joints.append((s.source_timestamp_ns, s.data))
            elif name == "/joint_states":
                robot_joints.setdefault(namespace, []).append((s.source_timestamp_ns, s.data))
            elif name in ("/tf", "/tf_static"):
                tf.setdefault(s.topic, []).append((s.source_timestamp_ns, s.data))
            elif name == "/robot_description":
                text = self._description(s)
                if text is not None and namespace:
                    batch.robot_descriptions.append((namespace, text))
                elif text is not None:
                    batch.descriptions.append(text)
            else:
                shown = batch.displays if s.ros_type in DECODERS else batch.fields
                shown.append(TopicMessage(s.source_timestamp_ns, s.topic, s.ros_type, s.data))
        batch.joints = self._decode_joints(joints)
        for namespace, messages in robot_joints.items():
            pending = self._robot_pending.setdefault(namespace, deque(maxlen=PENDING_JOINT_STATES))
            if (chunk := _held_or_decoded(self._robot_joints.get(namespace), pending, messages)) is not None:
                batch.robot_joints[namespace] = chunk
        for topic, messages in sorted(tf.items(), key=lambda item: not item[0].endswith("/tf_static")):
            records = self._decode_tf(topic, messages)
            if records is not None:
                namespace = topic.rpartition("/")[0]
                batch.tf.append(renamed(records, prefix_of(namespace), self.shared_frames))
        self._check_dropped()
        batch.notes, self._notes = self._notes, []
        return batch

    def problems(self) -> list[tuple[str, str]]:
        """At the end: the count of every kind of problem seen (``(topic, line)``)."""
        lines = self._joints.problems() if self._joints else []
        out = [("/joint_states", line) for line in lines if not line.startswith("ignored")]  # named when first seen
        for namespace, robot in sorted(self._robot_joints.items()):
            out += [(f"{namespace}/joint_states", line) for line in robot.problems()]
        for topic, decoder in self._tf.items():
            if decoder.bad:
                out.append((topic, f"skipped {decoder.bad} messages that cannot be decoded"))
            if self._tf_nonfinite[topic]:
                out.append((topic, f"skipped {self._tf_nonfinite[topic]} transforms with NaN or infinite values"))
        out += [(t, f"{n} messages dropped: the viewer fell behind") for t, n in sorted(self._dropped.items()) if n]
        return out

    def _note(self, key: str, line: str) -> None:
        self._notes.append((key, line))

    def _description(self, s: Sample) -> str | None:
        try:
            if len(s.data) > MAX_DESCRIPTION_BYTES:
                raise MsgError(f"{len(s.data)} bytes")
            return str(_deserialize(s.data, STRING).data)
        except MsgError as exc:
            self._note(f"description {s.topic}", f"{s.topic}: a message cannot be decoded: {exc}")
            return None

    def _decode_joints(self, messages: list[tuple[int, bytes]]) -> SampleChunk | None:
        if self._joints is None:
            self._pending.extend(messages)
            return None
        if self._pending:
            messages = [*self._pending, *messages]
            self._pending.clear()
        if not messages:
            return None
        chunk = self._joints.decode(messages)
        decoder = self._joints
        said = self._said_joint_problems
        if decoder.unknown and "unknown" not in said:
            said.add("unknown")
            names = f"{len(decoder.unknown)}: {listed(sorted(decoder.unknown))}"
            self._note("/joint_states unknown", f"/joint_states: ignored joints the robot does not have ({names})")
        for kind, what in JOINT_PROBLEMS.items():
            if getattr(decoder, kind) and kind not in said:
                said.add(kind)
                self._note(f"/joint_states {kind}", f"/joint_states: {what} (counted, said at the end)")
        return _time_sorted(chunk)

    def _decode_tf(self, topic: str, messages: list[tuple[int, bytes]]) -> TfRecords | None:
        if not messages:
            return None
        if topic not in self._tf:  # a robot's own /<namespace>/tf or /<namespace>/tf_static
            static = topic.endswith("/tf_static")
            self._tf[topic] = TfDecoder(_deserialize, static=static, time=self.time)
            self._tf_nonfinite[topic] = 0
        decoder = self._tf[topic]
        bad = decoder.bad
        records = decoder.decode(messages)
        if decoder.bad and not bad:
            self._note(f"{topic} bad", f"{topic}: a message cannot be decoded (further ones are counted)")
        finite = np.isfinite(records.translation).all(axis=1) & np.isfinite(records.quat_xyzw).all(axis=1)
        if not finite.all():
            if not self._tf_nonfinite[topic]:
                self._note(f"{topic} nonfinite", f"{topic}: transforms with NaN or infinite values are skipped")
            self._tf_nonfinite[topic] += int(np.count_nonzero(~finite))
            records = records.rows(np.flatnonzero(finite))
        return records if len(records) else None

    def _check_dropped(self) -> None:
        for topic, n in list(self.graph.dropped.items()):
            if n and not self._dropped.get(topic):
                self._note(
                    f"dropped {topic}",
                    f"{topic}: messages dropped, the viewer fell behind (oldest first; counted, said at the end)",
                )
            self._dropped[topic] = n


def _time_sorted(chunk: SampleChunk | None) -> SampleChunk | None:
    """``chunk`` in time order (several publishers' stamps may interleave); None when empty."""
    if chunk is None or not len(chunk):
        return None
    order = np.argsort(chunk.times_ns, kind="stable")
    return SampleChunk(chunk.times_ns[order], chunk.joints, chunk.positions[order])


def _held_or_decoded(
    decoder: JointStateDecoder | None, pending: deque[tuple[int, bytes]], messages: list[tuple[int, bytes]]
) -> SampleChunk | None:
    """A namespaced robot's joint states: kept in ``pending`` until its description gives a ``decoder``, then
    decoded with them (its problems counted by the decoder, said at the end)."""
    if decoder is None:
        pending.extend(messages)
        return None
    messages = [*pending, *messages]
    pending.clear()
    return _time_sorted(decoder.decode(messages)) if messages else None
