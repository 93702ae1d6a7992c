"""Writing to the live graph, for the web page's tools: one DDS writer per topic, reliable, volatile, depth 1 (as
RViz's tools publish), on the participant the app listens with. A message goes out as the CDR bytes rosbags'
``serialize_cdr`` made (encapsulation header included): the topic's raw type (:meth:`IdlTypes.raw_struct`) hands
them to Cyclone as they are, which is what ``DataWriter.write`` sends (``sample.serialize()``)."""

from __future__ import annotations

import threading
from collections.abc import Mapping
from types import ModuleType
from typing import Any

from r2d2_viz.sources.live.idl_types import IdlTypes
from r2d2_viz.sources.live.names import LiveError, dds_topic

MAX_BLOCKING_NS = 100_000_000
"""A reliable write waits at most 0.1 s for a slow reader's acknowledgements."""


class Writers:
    """The writers of one participant, made on first use."""

    def __init__(self, dds: Mapping[str, ModuleType], participant: Any, types: IdlTypes) -> None:
        self._dds, self._participant, self._types = dds, participant, types
        self._writers: dict[str, tuple[str, Any, Any]] = {}
        self._lock = threading.Lock()

    def publish(self, topic: str, ros_type: str, data: bytes) -> None:
        """Write ``data`` (CDR with its 4-byte header) on ``topic`` as ``ros_type``; LiveError if it cannot."""
        with self._lock:
            found = self._writers.get(topic)
            if found is None:
                found = self._writers[topic] = self._make(topic, ros_type)
        known, raw_type, writer = found
        if known != ros_type:
            raise LiveError(f"{topic} is published as {known}, not {ros_type}")
        sample = object.__new__(raw_type)  # the raw type's sample is its bytes: serialize() hands them over
        sample.serialize = lambda use_version_2=None: data
        try:
            writer.write(sample)
        except Exception as exc:
            raise LiveError(f"cannot publish on {topic}: {exc}") from None

    def _make(self, topic: str, ros_type: str) -> tuple[str, Any, Any]:
        core = self._dds["core"]
        policy = core.Policy
        qos = core.Qos(
            policy.Reliability.Reliable(max_blocking_time=MAX_BLOCKING_NS),
            policy.Durability.Volatile,
            policy.History.KeepLast(1),
        )
        try:
            raw_type = self._types.raw_struct(ros_type)
            entity = self._dds["topic"].Topic(self._participant, dds_topic(topic), raw_type)
            writer = self._dds["pub"].DataWriter(self._participant, entity, qos=qos)
        except LiveError:
            raise
        except Exception as exc:
            raise LiveError(f"cannot publish on {topic} ({ros_type}): {exc}") from None
        return ros_type, raw_type, writer
