"""Display topics into the recording, in time order, as far as a replay has got (like :class:`TfFeed` for
recorded transforms): each message decoded (:mod:`r2d2_viz.msgs`) and logged in its TF frame at its time.

An empty frame id is drawn in the fixed frame (said once per topic); a message that cannot be decoded is said once per
topic and counted (the count is said at the end). Odometry keeps RViz's history: a pose is kept only when it moved
Position Tolerance or turned Angle Tolerance from the last one kept (:mod:`~r2d2_viz.viewer.blocks.odometry_keep`),
and the poses kept go round ``<topic>/<k mod keep>`` (Keep, default 100), so the last ``keep`` stay in view.

Cameras become Rerun ``VideoStream`` s with ``--video``: :mod:`~r2d2_viz.viewer.blocks.video_feed`.
"""

from __future__ import annotations

import dataclasses
from collections import deque
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import rerun as rr

from r2d2_viz.errors import short
from r2d2_viz.msgs.blocks.markers import MarkerBlock
from r2d2_viz.msgs.nav import apply_grid_update
from r2d2_viz.msgs.registry import BLOCK_DECODERS
from r2d2_viz.msgs.rviz2.joined import Joins
from r2d2_viz.msgs.shapes import Decoded, DecodeOptions, GridMap, MarkerOp, MeshResource, is_plain
from r2d2_viz.msgs.typestore import MsgError
from r2d2_viz.sources.bag_displays import GRID_UPDATE, TopicMessage, camera_images
from r2d2_viz.sources.base import Clock, TfRecords
from r2d2_viz.sources.topic_blocks import TopicBlock
from r2d2_viz.viewer.blocks.block_feed import BlockFeed, TopicState
from r2d2_viz.viewer.blocks.display_columns import ColumnRuns, columnable
from r2d2_viz.viewer.blocks.image_overlays import on_image, overlay_frames
from r2d2_viz.viewer.blocks.marker_columns import MarkerColumns
from r2d2_viz.viewer.blocks.odometry_keep import OdometryKeep, Tolerance
from r2d2_viz.viewer.blocks.row_columns import RowColumns
from r2d2_viz.viewer.blocks.telemetry_columns import ROWS as READER_BLOCKS
from r2d2_viz.viewer.blocks.video_feed import VideoFeed as VideoFeed  # where runs build it
from r2d2_viz.viewer.decay import FixedFramePlacer
from r2d2_viz.viewer.displays import MeshLoader, expire_markers, log_decoded, prepare, set_time
from r2d2_viz.viewer.entities import TIMELINE
from r2d2_viz.viewer.notices import Notices

_FOREVER = 2**63 - 1
GRID = "nav_msgs/msg/OccupancyGrid"
FLUSH_BYTES = 64 << 20
"""Wait for the sinks after this many bytes of messages (clouds and images are megabytes each)."""
KEEP = {"nav_msgs/msg/Odometry": 100}
"""RViz's default history (its display's Keep) per type; every other display shows its latest message."""


@dataclass(frozen=True)
class DisplayStyle:
    """How one topic is drawn: RViz's defaults, or what an RViz config's display says."""

    options: DecodeOptions = field(default_factory=DecodeOptions)
    keep: int | None = None
    """History length (Odometry's Keep); None: the type's default."""
    decay: bool = False
    """RViz's Decay Time is set: the drawings are logged in the fixed frame (:mod:`r2d2_viz.viewer.decay`)."""
    tolerance: Tolerance = field(default_factory=Tolerance)
    """Odometry's Position and Angle Tolerance (:mod:`r2d2_viz.viewer.blocks.odometry_keep`)."""


class DisplayFeed(BlockFeed):
    """Decode and log display messages: a replay :meth:`push` es those of each stretch it reads and :meth:`until`
    logs what is due; a live source calls :meth:`log` as messages arrive."""

    def __init__(
        self,
        notices: Notices,
        *,
        clock: Clock,
        fixed_frame: str,
        header_time: bool = False,
        styles: Mapping[str, DisplayStyle] | None = None,
        load_mesh: MeshLoader | None = None,
        source_name: str = "",
        timeline: str = TIMELINE,
        topics: Mapping[str, str] | None = None,
        start_ns: int | None = None,
        tf: Sequence[TfRecords] = (),
        video: VideoFeed | None = None,
        hold: bool = False,
    ) -> None:
        self.notices, self.rec = notices, notices.rec
        self.video = video or VideoFeed(None)
        """Cameras as video (``--video``: raw images encoded) and video samples passed through."""
        self._pending: deque[TopicMessage] = deque()
        self.clock, self.fixed_frame, self.header_time = clock, fixed_frame, header_time
        self.styles = dict(styles or {})
        self.load_mesh, self.source_name, self.timeline = load_mesh, source_name, timeline
        self.topics: dict[str, TopicState] = {}
        self.cameras = camera_images(topics or {})
        self.overlays = overlay_frames(topics or {}, fixed_frame)  # 2D detections: on their camera's image
        """CameraInfo topic → the image topics of its camera: each gets the pinhole, so images show in 3D."""
        self._unflushed = 0
        self._flushes = not hold  # a batch run's only backpressure is the runner's (viewer/files/flush_ahead.py)
        self._topic_types = dict(topics or {})
        self.maps: dict[str, bytes] = {}
        """The latest OccupancyGrid (CDR) of each map topic: what its updates apply to."""
        self._start_ns = start_ns
        self._anchored: tuple[int, str] | None = None
        decayed = any(style.decay for style in self.styles.values())
        self._placer = FixedFramePlacer(tf, fixed_frame) if decayed else None
        self.on_map: Callable[[str, GridMap], object] | None = None
        """Called with each map drawn and its frame (the tools' ground grows to cover it)."""
        self.columns = ColumnRuns(self.rec, timeline, clock, hold=hold)  # images, points: columns (until())
        self.rows = RowColumns(self.rec, timeline, clock, hold=hold)  # every other display's rows: columns too
        self.odometry = OdometryKeep(lambda topic: (self.styles.get(topic) or DisplayStyle()).tolerance)
        self.joins = Joins({topic: style.options for topic, style in self.styles.items()})  # DepthCloud, Effort…
        self._init_blocks(hold, timeline, clock)  # a batch run's blocks of messages (issue 46): decode_block

    def _anchor(self, topics: Mapping[str, str], time_ns: int) -> None:
        """From the first message's time, every display entity (each slot of a history too) sits in the fixed
        frame until its own first message: the viewer then finds a transform path for each from the start
        (otherwise it reports "no transform path" for every entity not drawn yet)."""
        set_time(self.rec, self.timeline, time_ns, self.clock)
        self._anchored = (time_ns, self.fixed_frame)  # markers' entities too, from their first message
        for topic, msgtype in topics.items():
            keep = _keep(self.styles, topic, msgtype)
            for entity in [f"{topic}/{k}" for k in range(keep)] if keep > 1 else [topic]:
                self.rec.log(entity, rr.CoordinateFrame(self.fixed_frame))

    def push(self, messages: Iterable[TopicMessage], blocks: Sequence[TopicBlock] = ()) -> None:
        """Messages just read in receive-time order (and blocks of them); the first ones anchor every display entity."""
        self._push_blocks(blocks)
        for message in messages:
            if self._anchored is None and self._topic_types:  # from the run's start when that is earlier
                start = message.time_ns if self._start_ns is None else min(message.time_ns, self._start_ns)
                self._anchor(self._topic_types, start)
            self._pending.append(message)

    def add_tf(self, records: TfRecords | None) -> None:
        """Transforms just read: decayed displays are placed in the fixed frame with them."""
        if self._placer is not None and records is not None and len(records):
            self._placer.add(records)

    @property
    def next_time_ns(self) -> int | None:
        """The receive time of the next message not logged yet (None: none pending)."""
        return self._next_block_ns(self._pending[0].time_ns if self._pending else None)  # blocks too

    def until(self, time_ns: int | None = None) -> int:
        """Log the pending messages received up to ``time_ns`` (inclusive; all when None); how many were due."""
        due: list[TopicMessage] = []
        while self._pending and (time_ns is None or self._pending[0].time_ns <= time_ns):
            due.append(self._pending.popleft())
        alone, blocks = _blocks(self, self.odometry.kept(due))  # odometry first: before a pose takes a history slot
        for message in alone:
            message = self.decode(message)
            if _simple(self, message, message.decoded):
                entity = _count(self, message)[1]
                self.rows.send(entity, *self.cameras.get(message.topic, ()))
                self.columns.add(message, entity, self.cameras.get(message.topic, ()), header_time=self.header_time)
            else:  # on its own: after what its entities' runs hold, at the time the runs left
                self.columns.interrupt(message.topic, *self.cameras.get(message.topic, ()))
                self._log(message)
        _log_blocks(self, blocks)  # MarkerArrays a block at a time, decoded here
        self._until_blocks(time_ns, due)  # blocks the reader decoded (Imu): viewer/blocks/block_feed.py
        self.columns.interrupt(everything=time_ns is None)  # everything taken: held runs too
        end = _FOREVER if time_ns is None else time_ns
        for state in self.topics.values():  # markers whose lifetime ran out, even on a topic gone quiet
            if state.markers.live:
                expire_markers(self.rows, state.markers, self.timeline, end, self.clock)
        self.rows.window_end(everything=time_ns is None)
        return len(due)

    def log(self, *messages: TopicMessage) -> None:
        """Decode and log a live source's messages as they come (rows as columns), unless RViz would not draw them."""
        for message in self.odometry.kept(list(messages)):
            self._log(message)
        self.rows.window_end()

    def _log(self, message: TopicMessage) -> None:
        if message.msgtype == GRID_UPDATE:
            _update_map(self, message)
            return
        if message.msgtype == GRID:
            self.maps[message.topic] = bytes(message.data)
        state, slot = _count(self, message)
        style = self.styles.get(message.topic) or DisplayStyle()
        try:
            decoded = self.decode(message, now=True).decoded
            if isinstance(decoded, MsgError):
                raise decoded
            assert decoded is not None
        except MsgError as exc:
            state.problems += 1
            self.notices.report(
                f"{self._where(message.topic)}: a {message.msgtype} message cannot be shown: {exc} "
                "(further problems on this topic are counted)",
                key=f"display problem {message.topic}",
            )
            return
        for note in self.video.notes(message.topic):
            self.notices.report(f"{self._where(message.topic)}: {note}", key=f"video {message.topic} {note}")
        if not self.video.ready(self.rec, message.topic, decoded):
            return
        placed = _placed(self, message.topic, decoded)
        if self.on_map is not None and isinstance(placed, Decoded):
            for item in placed.items:
                if isinstance(item, GridMap):
                    self.on_map(placed.frame_id, item)
        if style.decay and self._placer is not None and isinstance(placed, Decoded):
            placed = self._placer.place(placed, message.time_ns)
        prepared = message.prepared if placed is decoded else None  # built for the frames it had
        decoded = placed
        time_ns = message.time_ns
        if self.header_time:
            stamp = decoded.stamp_ns if isinstance(decoded, Decoded) else _first_stamp(decoded)
            time_ns = stamp if stamp else time_ns
        entity = slot if isinstance(decoded, Decoded) else message.topic
        images = self.cameras.get(message.topic, ())
        times = [time_ns]
        if images and state.messages == 1 and self._anchored is not None and self._anchored[0] < time_ns:
            # a camera's first intrinsics from the run's start: its images are never without a pinhole in 3D
            times.insert(0, self._anchored[0])
        for t in times:
            for target in (entity, *images):
                log_decoded(
                    self.rows,
                    target,
                    decoded,
                    timeline=self.timeline,
                    time_ns=t,
                    clock=self.clock,
                    markers=state.markers,
                    load_mesh=self.load_mesh,
                    prepared=prepared,  # type: ignore[arg-type]  # what self.decode built: displays.Prepared
                    plain=state.plain,
                )

    def decode(self, message: TopicMessage, *, now: bool = False) -> TopicMessage:
        """``message`` with what it draws (or why not), in its style; pure: a bag's reader calls it (blocks: later)."""
        if message.decoded is not None or message.msgtype == GRID_UPDATE or (not now and _blocked(self, message)):
            return message  # updates: applied when logged
        style = self.styles.get(message.topic) or DisplayStyle()
        try:
            decoded: Decoded | list[MarkerOp] | MsgError = self.joins.decode(
                message.topic, message.msgtype, message.data, style.options
            )
            decoded = self.video.encode(message.topic, message.time_ns, decoded)
        except MsgError as exc:
            decoded = exc
        prepared = None
        if isinstance(decoded, Decoded) and _ahead(self, message, decoded):
            prepared = prepare(decoded)  # the archetypes too, off the logging thread
        return TopicMessage(message.time_ns, message.topic, message.msgtype, message.data, decoded, prepared)

    def _where(self, topic: str) -> str:  # the topic's problem follows: less room than in a list of names
        return f"{self.source_name}: {short(topic, 60)}" if self.source_name else short(topic, 60)

    def finish(self) -> None:
        """Send the runs still held; say, per topic, how many messages could not be shown (beyond the first)."""
        for runs in (self.columns, self.rows, self.block_runs):
            runs.send()
        for topic, note in self.video.finish():
            self.notices.report(f"{self._where(topic)}: {note}")
        for topic, state in self.topics.items():
            if state.problems > 1:
                self.notices.report(
                    f"{self._where(topic)}: {state.problems} of {state.messages} messages could not be shown"
                )


def _blocked(feed: DisplayFeed, message: TopicMessage) -> bool:
    """Whether ``message`` is decoded with its topic's others of the window (:data:`BLOCK_DECODERS`): a batch
    run's, not decayed, no ``--video``, times not the headers'."""
    if message.msgtype not in BLOCK_DECODERS or message.msgtype in READER_BLOCKS:  # those: the reader's blocks
        return False
    if feed._flushes or feed.header_time or feed.video.encoder:
        return False
    return not (feed.styles.get(message.topic) or DisplayStyle()).decay


def _blocks(feed: DisplayFeed, due: list[TopicMessage]) -> tuple[list[TopicMessage], dict[str, list[TopicMessage]]]:
    """The messages logged one by one, and those of each topic decoded a block at a time (:func:`_blocked`)."""
    alone: list[TopicMessage] = []
    blocks: dict[str, list[TopicMessage]] = {}
    for message in due:
        if _blocked(feed, message):
            blocks.setdefault(message.topic, []).append(message)
        else:
            alone.append(message)
    return alone, blocks


def _log_blocks(feed: DisplayFeed, blocks: dict[str, list[TopicMessage]]) -> None:
    """Each topic's messages of a window decoded together and logged as columns; those a block leaves (a
    DELETE, a lifetime, a problem to say) one by one, in their turn."""
    for topic, messages in blocks.items():
        options = (feed.styles.get(topic) or DisplayStyle()).options
        block = BLOCK_DECODERS[messages[0].msgtype]([m.data for m in messages], options)
        state = feed.topics.setdefault(topic, TopicState())
        state.markers.anchor = feed._anchored
        times = np.array([m.time_ns for m in messages], dtype=np.int64)
        if isinstance(block, MarkerBlock):
            MarkerColumns(feed.rows, feed.timeline, feed.clock, feed.load_mesh).log(
                topic,
                times,
                block,
                state.markers,
                own=lambda i, messages=messages: feed._log(messages[i]),  # type: ignore[misc]
                count=lambda i, messages=messages: _count(feed, messages[i]),  # type: ignore[misc]
            )


def _count(feed: DisplayFeed, message: TopicMessage) -> tuple[TopicState, str]:
    state = feed.topics.setdefault(message.topic, TopicState())
    state.markers.anchor = feed._anchored
    state.messages += 1
    feed._unflushed += len(message.data)
    if feed._flushes and feed._unflushed > FLUSH_BYTES:  # backpressure: big messages must not pile up (live)
        feed.rec.flush()
        feed._unflushed = 0
    keep = _keep(feed.styles, message.topic, message.msgtype)  # a history: <topic>/<k>, k = the message's slot
    on_image = feed.overlays.get(message.topic, (message.topic, ""))[0]  # a 2D detection: below its image's entity
    return state, f"{message.topic}/{(state.messages - 1) % keep}" if keep > 1 else on_image


def _keep(styles: Mapping[str, DisplayStyle], topic: str, msgtype: str) -> int:
    style = styles.get(topic) or DisplayStyle()
    return style.keep if style.keep is not None else KEEP.get(msgtype, 1)


def _simple(feed: DisplayFeed, message: TopicMessage, decoded: Decoded | list[MarkerOp] | MsgError | None) -> bool:
    """Whether the decoded message joins a run (:func:`columnable`): not decayed, no ``--video``."""
    decay = (feed.styles.get(message.topic) or DisplayStyle()).decay
    return not decay and feed.video.encoder is None and columnable(decoded, first=message.topic not in feed.topics)


def _update_map(feed: DisplayFeed, message: TopicMessage) -> None:
    """An OccupancyGridUpdate applied to the latest map of the topic it updates, as RViz's Map display does
    (``/costmap_updates`` updates ``/costmap``); the map is drawn again."""
    state = feed.topics.setdefault(message.topic, TopicState())
    state.messages += 1
    topic = message.topic.removesuffix("_updates")
    base = feed.maps.get(topic)
    try:
        if base is None:
            raise MsgError(f"no map on {topic} before it")
        updated = apply_grid_update(base, message.data)
    except MsgError as exc:
        state.problems += 1
        feed.notices.report(
            f"{feed.source_name + ': ' if feed.source_name else ''}{message.topic}: a map update cannot be applied: "
            f"{exc} (further problems on this topic are counted)",
            key=f"display problem {message.topic}",
        )
        return
    feed.log(TopicMessage(message.time_ns, topic, GRID, updated))


def _ahead(feed: DisplayFeed, message: TopicMessage, decoded: Decoded) -> bool:
    """Whether its archetypes are built ahead: in a frame, no mesh files (loaded when logged), not columns."""
    meshes = any(isinstance(item, MeshResource) for item in decoded.items)
    return bool(decoded.frame_id) and not meshes and not _simple(feed, message, decoded)


def _first_stamp(ops: list[MarkerOp]) -> int:
    return next((op.decoded.stamp_ns for op in ops if op.decoded is not None and op.decoded.stamp_ns), 0)


def _placed(feed: DisplayFeed, topic: str, decoded: Decoded | list[MarkerOp]) -> Decoded | list[MarkerOp]:
    """An empty frame id → the fixed frame (said once per topic); a 2D detection → its image's frame."""
    decoded = on_image(decoded, feed.overlays.get(topic, ("", None))[1])

    def fix(d: Decoded) -> Decoded:
        if d.frame_id or all(is_plain(item) for item in d.items):  # a log, a plot: in no frame
            return d
        feed.notices.report(
            f"{feed._where(topic)}: messages with an empty frame_id are drawn in the fixed frame [{feed.fixed_frame}]",
            key=f"empty frame {topic}",
        )
        return dataclasses.replace(d, frame_id=feed.fixed_frame)

    if isinstance(decoded, Decoded):
        return fix(decoded)
    return [dataclasses.replace(op, decoded=fix(op.decoded)) if op.decoded else op for op in decoded]
