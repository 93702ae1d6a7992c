"""A run as a stream of :class:`Window` s, the stretches of time every consumer takes in turn: a generated motion's
chunks, or a bag read **once**, in time order, each stretch dispatched by topic — ``/joint_states`` to one
:class:`~r2d2_viz.sources.base.SampleChunk` (decoded in bulk), ``/tf`` to transform rows, display topics to raw
messages. Windows are bounded (samples, bytes), so memory stays flat whatever the bag's size; :func:`read_ahead`
reads and decodes the next windows in a thread while the current one is written (both cores).

Pure: no rerun import.
"""

from __future__ import annotations

import itertools
import queue
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from r2d2_viz.msgs.registry import BLOCK_DECODERS
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.sources.bag_joints import JOINT_STATE, JointStateDecoder, TimeSource, monotonic
from r2d2_viz.sources.bag_tf import TF_MESSAGE, TfDecoder, concatenate
from r2d2_viz.sources.bags.bag import Bag
from r2d2_viz.sources.bags.storage import Block
from r2d2_viz.sources.base import SampleChunk, Source, TfRecords, last_per_time
from r2d2_viz.sources.fields_pass import FieldsPass, TopicColumns
from r2d2_viz.sources.robots import renamed
from r2d2_viz.sources.topic_blocks import BlockPredecoder, TopicBlock

JOINTS, TF = "/joint_states", "/tf"
WINDOW_BYTES = 8 << 20
"""A window holds about this many bytes of messages at most (a few images and clouds; a window's messages stay in
memory until written, a few windows at once: a .db3 bag's are the program's own memory, 32 MB windows peaked at
371 MB on the 2.8 GB sensor bag, 8 MB ones at 270 MB, at the same CPU time)…"""
LIVE_WINDOW_BYTES = 4 << 20
"""…and a live replay's, this many: its first data goes out as soon as the first few megabytes are read."""


@dataclass(frozen=True, eq=False)
class Window:
    """One stretch of a run: everything received up to ``end_ns`` that the previous windows did not hold."""

    end_ns: int
    joints: SampleChunk | None = None
    tf: TfRecords | None = None
    displays: tuple[TopicMessage, ...] = ()
    nbytes: int = 0
    """Bytes of bag messages in it (progress)."""
    more_joints: tuple[SampleChunk | None, ...] = ()
    """Several robots: the joint states of the second, third… (``joints`` holds the first's)."""
    fields: tuple[TopicColumns, ...] = ()
    """Other topics' fields (:mod:`r2d2_viz.sources.fields_pass`)."""
    blocks: tuple[TopicBlock, ...] = ()
    """Display messages decoded a topic at a time (:mod:`r2d2_viz.sources.topic_blocks`), not in ``displays``."""


def source_windows(source: Source, max_samples: int) -> Iterator[Window]:
    """A generated motion's chunks as windows."""
    for chunk in source.chunks(max_samples):
        yield Window(int(chunk.times_ns[-1]) if len(chunk) else 0, joints=chunk)


@dataclass(frozen=True)
class Segment:
    """A stretch ``[start_ns, stop_ns)`` of the bag and the topics read in it."""

    topics: tuple[str, ...]
    start_ns: int | None = None
    stop_ns: int | None = None


class BagPass:
    """The bag's wanted topics read once, in time order, as windows (see the module docstring). ``actuated``: the
    robot's joints (None: joint states are not read); ``displays``: display topic → type. Several robots
    (:mod:`r2d2_viz.sources.robots`): ``robots`` lists each one's joint-states topic and joints (None: not read) and
    replaces ``actuated``; ``tf_topics`` maps each TF topic read to the prefix its frames take."""

    def __init__(
        self,
        bag: Bag,
        segments: Sequence[Segment],
        *,
        actuated: Sequence[str] | None,
        displays: Mapping[str, str],
        time: TimeSource = "receive",
        quiet: bool = False,
        predecode: Callable[[TopicMessage], TopicMessage] | None = None,
        robots: Sequence[tuple[str, Sequence[str] | None]] = (),
        tf_topics: Mapping[str, str] | None = None,
        shared: Sequence[str] = (),
        fields: FieldsPass | None = None,
    ) -> None:
        self.bag, self.segments, self.displays, self.time = bag, tuple(segments), dict(displays), time
        self.fields = fields
        """Decodes the other topics' fields (read in the last segment: not in a seek's preroll)."""
        if fields is not None and self.segments:
            last = self.segments[-1]
            topics = (*last.topics, *(t for t in fields.topics if t not in last.topics))
            self.segments = (*self.segments[:-1], Segment(topics, last.start_ns, last.stop_ns))
        self.quiet = quiet
        """Say nothing of what was skipped (a look-ahead: the pass itself says it)."""
        self.predecode = predecode
        """Decodes each display message as it is read (in :func:`read_ahead`'s thread, beside the writing)."""
        owner: BlockPredecoder | None = getattr(predecode, "__self__", None)
        self.decode_block = getattr(owner, "decode_block", None)
        """The predecoder's owner's (the display feed's) block decoding, when it has one: a topic's messages of a
        piece at once (issue 46)."""
        self.joints_topic = robots[0][0] if robots else JOINTS
        if robots:
            actuated = robots[0][1]
        self.joints = JointStateDecoder(actuated, time=time, deserialize=bag.deserialize) if actuated else None
        self.others = [
            (topic, JointStateDecoder(joints, time=time, deserialize=bag.deserialize) if joints else None)
            for topic, joints in robots[1:]
        ]
        self._others_last = [(np.iinfo(np.int64).min, 0) for _ in self.others]
        self.tf = TfDecoder(bag.deserialize, static=False, time=time)
        self.tf_topics = dict(tf_topics) if tf_topics is not None else {TF: ""}
        self.shared = tuple(shared)
        self.read_ns = 0
        """How far the pass has read (receive time)."""
        self._last_ns = np.iinfo(np.int64).min
        self._moved = 0

    def windows(self, max_samples: int, max_bytes: int = WINDOW_BYTES) -> Iterator[Window]:
        """Every window, each with at most ``max_samples`` joint states and about ``max_bytes`` read from the bag
        (the storages' blocks gathered or cut to that size). What is read, not what is kept: a few small topics of
        a bag of compressed chunks would otherwise gather most of the file's chunks in one window (each one read
        whole), and a live replay's first window would wait for all of them."""
        pending: list[Block] = []
        size = samples = 0
        for segment in self.segments:
            for block in self.bag.blocks(segment.topics, start_ns=segment.start_ns, stop_ns=segment.stop_ns):
                for piece in self._pieces(block, max_samples, max_bytes):
                    n = len(piece.rows(self.joints_topic)) if self.joints is not None else 0
                    full = size + piece.cost > max_bytes or samples + n > max_samples
                    if pending and full and not _tied(pending[-1], piece, samples, max_samples):
                        yield self._window(pending)
                        pending, size, samples = [], 0, 0
                    pending.append(piece)
                    size, samples = size + piece.cost, samples + n
        if pending:
            yield self._window(pending)
        self._finish()

    def _pieces(self, block: Block, max_samples: int, max_bytes: int) -> Iterator[Block]:
        """``block`` cut where it holds ``max_samples`` joint states or ``max_bytes``."""
        joint_rows = block.rows(self.joints_topic) if self.joints is not None else np.zeros(0, dtype=np.int64)
        cuts = {0, len(block)}
        if len(joint_rows) > max_samples:  # a long stretch of joint states: cut where a chunk is full
            cuts |= {int(r) for r in joint_rows[max_samples::max_samples]}
        if block.nbytes > max_bytes:
            sizes = np.cumsum(block.lengths)
            cuts |= {int(r) for r in np.searchsorted(sizes, np.arange(max_bytes, sizes[-1], max_bytes))}
        # a cut never falls between messages received at one time (one sample of them: :func:`last_per_time`)
        edges = sorted(
            {int(e) for e in np.searchsorted(block.times_ns, block.times_ns[sorted(cuts)[:-1]])} | {len(block)}
        )
        if len(edges) == 2:
            yield block
            return
        share = block.read_nbytes / max(block.nbytes, 1)  # what was read for the block, shared by bytes
        for lo, hi in itertools.pairwise(edges):
            if hi > lo:
                piece = block.take(np.arange(lo, hi))
                yield replace(piece, read_nbytes=int(share * piece.nbytes))

    def _window(self, pieces: list[Block]) -> Window:
        chunks: list[SampleChunk] = []
        records: list[TfRecords] = []
        messages: list[TopicMessage] = []
        blocks: list[TopicBlock] = []
        others: list[list[SampleChunk]] = [[] for _ in self.others]
        fields: list[TopicColumns] = []
        for block in pieces:
            if self.fields is not None:
                fields += self.fields.decode(block)
            if self.joints is not None and len(rows := block.rows(self.joints_topic)):
                chunk = self.joints.decode_block(block.take(rows))
                if chunk is not None:
                    chunk, self._last_ns, self._moved = monotonic(chunk, self._last_ns, self._moved)
                    chunks.append(last_per_time(chunk))
            for i, (topic, decoder) in enumerate(self.others):
                if decoder is not None and len(rows := block.rows(topic)):
                    chunk = decoder.decode_block(block.take(rows))
                    if chunk is not None:
                        chunk, last_ns, moved = monotonic(chunk, *self._others_last[i])
                        self._others_last[i] = (last_ns, moved)
                        others[i].append(last_per_time(chunk))
            for topic, prefix in self.tf_topics.items():
                if len(rows := block.rows(topic)):
                    decoded = self.tf.decode(block.take(rows).pairs())
                    records.append(renamed(decoded, prefix, self.shared) if prefix else decoded)
            for topic, msgtype in self.displays.items():
                piece = block.take(block.rows(topic))
                pairs = piece.pairs()
                if self.decode_block is not None and len(pairs) > 1 and msgtype in BLOCK_DECODERS:
                    decoded = self.decode_block(topic, msgtype, piece.times_ns, [data for _, data in pairs])
                    if decoded is not None:
                        blocks.append(decoded)
                        continue
                for t, data in pairs:
                    messages.append(TopicMessage(t, topic, msgtype, data))
        messages.sort(key=lambda m: m.time_ns)
        if self.predecode is not None:
            messages = [self.predecode(m) for m in messages]
        self.read_ns = int(pieces[-1].times_ns[-1])
        tf = concatenate([r for r in records if len(r)])
        more = tuple(_joined(c) for c in others)
        nbytes = sum(p.nbytes for p in pieces)
        return Window(self.read_ns, _joined(chunks), tf, tuple(messages), nbytes, more, tuple(fields), tuple(blocks))

    def _finish(self) -> None:
        if self.quiet:
            return
        if self.fields is not None:
            self.fields.finish()
        warn, path = self.bag.warn, self.bag.path
        decoders = [(self.joints_topic, self.joints, self._moved)]
        decoders += [(t, d, last[1]) for (t, d), last in zip(self.others, self._others_last, strict=True)]
        for topic, decoder, moved in decoders:
            for problem in decoder.problems() if decoder is not None else ():
                warn(f"{path}: {topic}: {problem}")
            if moved:
                stamps = "header stamps" if self.time == "header" else "receive times"
                warn(f"{path}: {topic}: {moved} {stamps} went back in time; they are shown at the previous one")
        if self.tf.bad:
            tf = TF if len(self.tf_topics) == 1 else "TF topics"
            warn(f"{path}: {tf}: skipped {self.tf.bad} messages that cannot be decoded")


def _tied(before: Block, after: Block, samples: int, max_samples: int) -> bool:
    """Whether ``after`` starts at the time ``before`` ends (a window is not cut there, unless it already holds twice
    its samples: a bag whose messages all share one time still comes in bounded windows)."""
    return int(after.times_ns[0]) == int(before.times_ns[-1]) and samples < 2 * max_samples


def bag_topics_read(bag: Bag, actuated: Sequence[str] | None, displays: Mapping[str, str]) -> tuple[str, ...]:
    """The topics a pass reads: joint states (with a robot), ``/tf``, the display topics."""
    wanted = [*displays]
    if actuated and bag.require_type(JOINTS, JOINT_STATE):
        wanted.append(JOINTS)
    if bag.require_type(TF, TF_MESSAGE):
        wanted.append(TF)
    return tuple(wanted)


def _joined(chunks: list[SampleChunk]) -> SampleChunk | None:
    """Consecutive chunks as one (their joints united; NaN where a chunk did not give a joint)."""
    if len(chunks) <= 1:
        return chunks[0] if chunks else None
    joints = tuple(dict.fromkeys(j for c in chunks for j in c.joints))
    if all(c.joints == joints for c in chunks):
        positions = np.vstack([c.positions for c in chunks])
    else:
        column = {j: i for i, j in enumerate(joints)}
        positions = np.full((sum(len(c) for c in chunks), len(joints)), np.nan)
        at = 0
        for c in chunks:
            positions[at : at + len(c), [column[j] for j in c.joints]] = c.positions
            at += len(c)
    return SampleChunk(np.concatenate([c.times_ns for c in chunks]), joints, positions)


_DONE = object()


def read_ahead(windows: Iterator[Window], depth: int = 2) -> Iterator[Window]:
    """``windows``, read and decoded ``depth`` ahead in a thread (the bag's reading beside the recording's writing).
    An exception in the reader comes out here; stopping early (Ctrl-C) stops the reader."""
    out: queue.Queue[object] = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def hand(item: object) -> bool:
        """Queue ``item`` unless the consumer has stopped (then nobody would take it)."""
        while not stop.is_set():
            try:
                out.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def read() -> None:
        try:
            for window in windows:
                if not hand(window):
                    return
            hand(_DONE)
        except BaseException as exc:  # handed to the consumer, raised there
            hand(exc)

    thread = threading.Thread(target=read, name="r2d2-viz bag reader", daemon=True)
    thread.start()
    try:
        while True:
            item = out.get()
            if item is _DONE:
                return
            if isinstance(item, BaseException):
                raise item
            assert isinstance(item, Window)
            yield item
    finally:
        stop.set()
