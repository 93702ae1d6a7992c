"""A bag's display topics — what RViz's displays draw: scans, clouds, markers, maps, paths, poses, images
(the types of :data:`r2d2_viz.msgs.registry.DECODERS`) — as one stream of raw messages in receive-time order,
read lazily from either storage; and what such a bag's frames say about where to look. Pure: no rerun.
"""

from __future__ import annotations

import heapq
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from r2d2_viz.msgs.registry import DECODERS, decode
from r2d2_viz.msgs.shapes import Decoded
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bags.bag import Bag

OURS = ("/joint_states", "/tf", "/tf_static", "/robot_description")
"""Topics the robot pipeline itself reads."""
BATCH = 16
"""Messages read ahead per topic: a cloud or an image is megabytes, so a few at a time."""


@dataclass(frozen=True)
class TopicMessage:
    """One message of a display topic as it was recorded or received: raw CDR bytes."""

    time_ns: int
    """Receive time (a bag's log time, a live sample's source timestamp)."""
    topic: str
    msgtype: str
    data: bytes | memoryview


def display_topics(bag: Bag) -> tuple[dict[str, str], dict[str, str]]:
    """``(topic → type)`` of the bag's topics a display draws, and of the others (not ours, no display)."""
    shown: dict[str, str] = {}
    other: dict[str, str] = {}
    for topic, info in sorted(bag.topics.items()):
        if topic in OURS:
            continue
        (shown if info.msgtype in DECODERS else other)[topic] = info.msgtype
    return shown, other


def bag_messages(bag: Bag, topics: Mapping[str, str]) -> Iterator[TopicMessage]:
    """Every message of ``topics``, merged across topics by receive time (each topic read lazily)."""

    def one(topic: str, msgtype: str) -> Iterator[TopicMessage]:
        for batch in bag.batches(topic, BATCH):
            yield from (TopicMessage(int(t), topic, msgtype, data) for t, data in batch)

    return heapq.merge(*(one(t, m) for t, m in topics.items()), key=lambda m: m.time_ns)


def display_frames(bag: Bag, topics: Mapping[str, str], *, per_topic: int = 3) -> set[str]:
    """The frames the first few messages of each display topic are drawn in (empty ids left out)."""
    frames: set[str] = set()
    for topic, msgtype in topics.items():
        for _, data in next(iter(bag.batches(topic, per_topic)), []):
            try:
                decoded = decode(msgtype, data)
            except MsgError:
                continue
            parts = [decoded] if isinstance(decoded, Decoded) else [op.decoded for op in decoded if op.decoded]
            frames.update(d.frame_id for d in parts if d.frame_id)
    return frames
