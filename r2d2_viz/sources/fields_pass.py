"""Every other topic of a bag decoded in its one pass: the topics no display draws, all their fields, with the
definitions the bag carries (:mod:`r2d2_viz.msgs.generic.decoder`); and the topics ``--plot`` paths name, just those
fields. A topic that cannot be decoded (no usable definition) is known before the pass and named once; bad
messages are counted per topic and said once, at the end. Pure: no rerun import.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from r2d2_viz.errors import BagError, listed
from r2d2_viz.msgs.generic.decoder import SEQ, FieldDecoder, topic_store
from r2d2_viz.msgs.generic.fields import Columns
from r2d2_viz.msgs.generic.message_path import MessagePath, check_field, field_names, parse_path
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.bags.storage import Block

TopicColumns = tuple[str, Columns]
STAMP = ("header.stamp.sec", "header.stamp.nanosec")
"""Read with every plotted field under ``--time header`` (a plot's points go there)."""


class FieldsPass:
    """``shown``: topic → type of the topics whose every field is shown; ``plots``: the ``--plot`` paths (checked:
    :func:`plot_paths`); ``stamps``: their header stamps too (``--time header``)."""

    def __init__(
        self, bag: Bag, shown: Mapping[str, str], plots: Sequence[MessagePath] = (), *, stamps: bool = False
    ) -> None:
        self.bag = bag
        self.decoders: dict[str, FieldDecoder] = {}
        self.unusable: dict[str, str] = {}
        """Topics that cannot be decoded → why."""
        self.variants: dict[tuple[str, int], FieldDecoder] = {}
        """(topic, storage file) → its decoder where that file defines the topic otherwise than the first."""
        wanted: dict[str, set[str]] = {}
        for p in plots:
            wanted.setdefault(p.topic, set()).update(
                [p.field, *(f.field for f in p.filters), *(STAMP if stamps else ())]
            )
        for topic in sorted({*shown, *wanted}):
            try:
                store = store_of(bag, topic)
            except MsgError as exc:
                self.unusable[topic] = str(exc)
                continue
            keep = frozenset(wanted.get(topic, ()))
            names = None if topic in shown else keep
            info, ros1 = bag.topics[topic], bag.topics[topic].encoding == "ros1msg" and topic not in bag.humble_topics
            self.decoders[topic] = FieldDecoder(store, info.msgtype, names, keep, ros1=ros1)
            if topic not in bag.humble_topics:
                self._variants(topic, names, keep)

    def _variants(self, topic: str, names: frozenset[str] | None, keep: frozenset[str]) -> None:
        """Decoders for the files of the bag whose definition of ``topic`` is another than the first one's (a
        message type changed between recordings): each file's messages are read with their own."""
        first = self.bag.topics[topic]
        made: dict[tuple[str, str], FieldDecoder] = {}
        for k in range(len(self.bag.files)):
            info = self.bag.file_topic(topic, k)
            if (
                info is None
                or not info.definition
                or (info.definition, info.encoding)
                == (
                    first.definition,
                    first.encoding,
                )
            ):
                continue
            if (key := (info.definition, info.encoding)) not in made:
                try:
                    store = topic_store(info.msgtype, info.definition, info.encoding)
                except MsgError:
                    continue  # read with the first one's: what does not fit it is counted, never shown
                made[key] = FieldDecoder(store, info.msgtype, names, keep, ros1=info.encoding == "ros1msg")
            self.variants[(topic, k)] = made[key]

    @property
    def topics(self) -> tuple[str, ...]:
        return tuple(self.decoders)

    def decode(self, block: Block) -> list[TopicColumns]:
        """The fields of the messages of ``block`` on the decoded topics."""
        out: list[TopicColumns] = []
        buf: np.ndarray | None = None
        for topic, decoder in self.decoders.items():
            rows = block.rows(topic)
            if not len(rows):
                continue
            if buf is None:
                buf = np.frombuffer(block.buffer, dtype=np.uint8)
            starts, lengths = block.starts[rows], block.lengths[rows]
            decoder = self.variants.get((topic, block.file), decoder)
            seq = None if block.seq is None else block.seq[rows]
            out += [(topic, c) for c in decoder.decode(buf, starts, lengths, block.times_ns[rows], seq) if len(c)]
        return out

    def finish(self) -> None:
        """Say each topic's problems, once; NaN and infinities (kept: gaps in a plot) in one line for all topics."""
        variants = {id(d): (t, d) for (t, _), d in self.variants.items()}  # one per definition, not per file
        for topic, decoder in (*self.decoders.items(), *variants.values()):
            if lines := decoder.problems.lines(nonfinite=False):
                self.bag.warn(f"{self.bag.path}: {topic}: {'; '.join(lines)}")
        nan = {t: d.problems.nonfinite for t, d in self.decoders.items() if d.problems.nonfinite}
        if nan:
            said = listed(f"{t} ({n})" for t, n in nan.items())
            self.bag.warn(f"{self.bag.path}: messages with NaN or infinity in a field (shown as they are): {said}")


def store_of(bag: Bag, topic: str):  # type: ignore[no-untyped-def]  # rosbags' Typestore, imported lazily
    info = bag.topics[topic]
    return topic_store(info.msgtype, info.definition, info.encoding, humble=topic in bag.humble_topics)


def plot_paths(bag: Bag, texts: Sequence[str]) -> tuple[MessagePath, ...]:
    """``--plot`` paths checked against the bag's topics and their definitions; a ``BagError`` naming the topic's
    fields when one names nothing."""
    out = []
    for text in texts:
        try:
            path = parse_path(text, set(bag.topics))
        except MsgError as exc:
            raise BagError(f"--plot {exc}") from None
        if path.topic not in bag.topics:
            raise BagError(
                f"--plot {text}: {bag.path} has no topic {path.topic} (its topics: {listed(sorted(bag.topics))})"
            )
        try:
            store = store_of(bag, path.topic)
        except MsgError as exc:
            raise BagError(f"--plot {text}: {exc}") from None
        msgtype = bag.topics[path.topic].msgtype
        whys = [
            None if path.field == SEQ and has_seq(bag, path.topic) else check_field(store, msgtype, path.field),
            *(check_field(store, msgtype, f.field, text=True) for f in path.filters),
        ]
        if (why := next((w for w in whys if w is not None), None)) is not None:
            names = field_names(store, msgtype)
            raise BagError(f"--plot {text}: {why}; {path.topic}'s fields: {listed(names, first=8)}")
        out.append(path)
    return tuple(out)


def has_seq(bag: Bag, topic: str) -> bool:
    """Whether ``topic``'s messages carry ROS 1's ``header.seq`` (a ROS 1 type that starts with a header)."""
    info = bag.topics[topic]
    if info.encoding != "ros1msg" or not info.definition:
        return False
    try:
        fields = topic_store(info.msgtype, info.definition, info.encoding).fielddefs[info.msgtype][1]
    except (MsgError, KeyError):
        return False
    return bool(fields) and fields[0][1] == (2, "std_msgs/msg/Header")
