"""The display feed's blocks (issue 46): a batch run's messages of a topic whose type has a block decoder
(:data:`r2d2_viz.msgs.registry.BLOCK_DECODERS`) come from the bag's reader thread as one
:class:`~r2d2_viz.sources.topic_blocks.TopicBlock` a window (:meth:`BlockFeed.decode_block`), wait beside the
messages that go one by one, and are logged as columns when due (:mod:`~r2d2_viz.viewer.blocks.telemetry_columns`).
:class:`BlockFeed` is mixed into :class:`r2d2_viz.viewer.display_feed.DisplayFeed`."""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import rerun as rr

from r2d2_viz.msgs.blocks.telemetry_blocks import MessageBlock
from r2d2_viz.msgs.registry import BLOCK_DECODERS
from r2d2_viz.msgs.shapes import DecodeOptions
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.sources.topic_blocks import TopicBlock
from r2d2_viz.viewer.blocks.plain_log import PlainBook
from r2d2_viz.viewer.blocks.row_columns import RowColumns
from r2d2_viz.viewer.blocks.telemetry_columns import ROWS, BlockRuns
from r2d2_viz.viewer.blocks.video_feed import VideoFeed
from r2d2_viz.viewer.displays import Clock, MarkerBook


@dataclass
class TopicState:
    """What the feed counts and remembers per display topic."""

    messages: int = 0
    problems: int = 0
    markers: MarkerBook = field(default_factory=MarkerBook)
    plain: PlainBook = field(default_factory=PlainBook)


class BlockFeed:
    """Blocks of messages beside the display feed's one-by-one path (the feed's attributes below are its own)."""

    rec: rr.RecordingStream
    rows: RowColumns
    topics: dict[str, TopicState]
    styles: dict[str, Any]
    cameras: Mapping[str, Any]
    overlays: Mapping[str, Any]
    video: VideoFeed
    header_time: bool
    _anchored: tuple[int, str] | None
    _unflushed: int
    _topic_types: dict[str, str]
    _start_ns: int | None

    def _anchor(self, topics: Mapping[str, str], time_ns: int) -> None:
        raise NotImplementedError  # the feed's

    def _init_blocks(self, hold: bool, timeline: str, clock: Clock) -> None:
        self._blocks: deque[TopicBlock] = deque()
        self._hold = hold
        self.block_runs = BlockRuns(self.rec, timeline, clock)

    def _push_blocks(self, blocks: Sequence[TopicBlock]) -> None:
        """Blocks just read (before the window's messages): the first ones anchor every display entity."""
        if blocks and self._anchored is None and self._topic_types:
            first = min(int(b.times_ns[0]) for b in blocks)
            self._anchor(self._topic_types, first if self._start_ns is None else min(first, self._start_ns))
        self._blocks.extend(blocks)

    def _next_block_ns(self, message_ns: int | None) -> int | None:
        """The earliest receive time not logged yet: ``message_ns`` (the next message's) or a block's."""
        times = [int(b.times_ns[0]) for b in self._blocks]
        return min([*times, message_ns] if message_ns is not None else times, default=None)

    def decode_block(
        self, topic: str, msgtype: str, times_ns: np.ndarray, messages: Sequence[bytes | memoryview]
    ) -> TopicBlock | None:
        """A window's messages of ``topic`` as one block when its type has a block decoder and a batch run draws it
        plainly (no decay, ``--video``, header time; no camera, no empty frame id); None: one by one. Pure, like the
        feed's ``decode``: a bag's reader thread calls it."""
        style = self.styles.get(topic)
        decoder = BLOCK_DECODERS.get(msgtype) if msgtype in ROWS else None  # MarkerArrays: in the feed (_log_blocks)
        drawn_apart = self.header_time or topic in self.cameras or topic in self.overlays or self.video.encoder
        if decoder is None or not self._hold or drawn_apart or (style is not None and style.decay) or len(messages) < 2:
            return None
        try:
            with np.errstate(all="ignore"):
                block = decoder(messages, style.options if style is not None else DecodeOptions())
        except (ValueError, IndexError, TypeError, OverflowError):  # what the per-message decoders say better
            return None
        if not isinstance(block, MessageBlock) or "" in getattr(block, "frames", ()):  # an empty frame: said once,
            return None  # drawn in the fixed one; None: what the block did not read exactly
        return TopicBlock(np.asarray(times_ns, dtype=np.int64), topic, msgtype, block, sum(len(m) for m in messages))

    def _until_blocks(self, time_ns: int | None, due: list[TopicMessage]) -> None:
        """Log the blocks' messages received up to ``time_ns`` (all when None), after the ``due`` messages logged one
        by one: the recording's time is left at the latest of them all (logging them in time order would have). The
        run's end (None) sends every run of rows held."""
        if not self._blocks:
            if time_ns is None:
                self.block_runs.send()
            return
        kept: deque[TopicBlock] = deque()
        after = latest = due[-1].time_ns if due else None
        for block in self._blocks:
            now, rest = block.split(time_ns) if time_ns is not None else (block, None)
            if rest is not None:
                kept.append(rest)
            if now is None:
                continue
            state = self.topics.setdefault(now.topic, TopicState())
            state.markers.anchor = self._anchored
            state.messages += len(now)
            self._unflushed += now.nbytes
            self.rows.send(now.topic)  # rows its messages logged one by one left (a block that fell back)
            ROWS[now.msgtype](self.block_runs, now.topic, now, state.plain)
            last = int(now.times_ns[-1])
            latest = last if latest is None else max(latest, last)
        self._blocks = kept
        if latest is not None and (after is None or latest > after):
            self.rows.at(latest)
        if time_ns is None:
            self.block_runs.send()
