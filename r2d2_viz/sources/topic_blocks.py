"""A window's messages of one display topic decoded together (issue 46): :class:`TopicBlock`, what a bag's reader
thread hands the display feed instead of a :class:`~r2d2_viz.sources.bag_displays.TopicMessage` per message when
the topic's type has a block decoder (:data:`r2d2_viz.msgs.registry.BLOCK_DECODERS`) and the run draws it plainly
(a batch run: no decay, ``--video`` or ``--header-time``). Pure: no rerun."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from r2d2_viz.msgs.blocks.telemetry_blocks import MessageBlock


@dataclass(frozen=True, eq=False)
class TopicBlock:
    """Messages of ``topic`` received at ``times_ns`` (ascending), decoded as one ``block`` (a row a message)."""

    times_ns: np.ndarray
    topic: str
    msgtype: str
    block: MessageBlock
    nbytes: int

    def __len__(self) -> int:
        return len(self.times_ns)

    def split(self, time_ns: int) -> tuple[TopicBlock | None, TopicBlock | None]:
        """The messages received up to ``time_ns`` (inclusive) and the rest (None: none)."""
        k = int(np.searchsorted(self.times_ns, time_ns, side="right"))
        if k == len(self):
            return self, None
        if k == 0:
            return None, self
        share, n = self.nbytes * k // len(self), len(self)
        head = TopicBlock(self.times_ns[:k], self.topic, self.msgtype, self.block.sliced(0, k), share)
        return head, TopicBlock(
            self.times_ns[k:], self.topic, self.msgtype, self.block.sliced(k, n), self.nbytes - share
        )


class BlockPredecoder(Protocol):
    """What decodes a window's messages of one topic as a block in a bag's reader thread (the display feed)."""

    def decode_block(
        self, topic: str, msgtype: str, times_ns: np.ndarray, messages: Sequence[bytes | memoryview]
    ) -> TopicBlock | None:
        """The messages as one block, or None: they go one by one."""
