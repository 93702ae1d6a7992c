"""Several storage files of one bag read as one stream in receive-time order (rosbag2 splits a recording by size or
duration, and a recorder may write files that overlap in time: several recorders in one folder, a split at a
cache flush).

Files whose spans do not overlap are read one after the other, block for block, at no extra cost; only where spans
overlap are the files' blocks merged (a k-way merge over time-ordered block streams): at each step every message
up to the earliest last time of the streams' current blocks is taken, and the pieces joined into one block in time
order (messages received at one time keep the files' order). Only those merged pieces are copied.

Pure: no rerun import.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from r2d2_viz.sources.bags.storage import Block, in_time_order

Span = tuple[int, int] | None


def overlapping_files(spans: Sequence[Span]) -> list[list[int]]:
    """Indices of files (given sorted by first time; None spans last) grouped where their spans overlap."""
    groups: list[list[int]] = []
    end = -1
    for i, span in enumerate(spans):
        if span is not None and groups and span[0] < end:  # starts before the group ends: merged with it
            groups[-1].append(i)
            end = max(end, span[1])
        else:
            groups.append([i])
            end = span[1] if span is not None else -1
    return groups


def merged(streams: Sequence[Iterator[Block]]) -> Iterator[Block]:
    """The blocks of several time-ordered block streams as one time-ordered stream (see the module docstring)."""
    iters = list(streams)
    heads: list[Block | None] = [_next(it) for it in iters]
    at = [0] * len(iters)
    while True:
        active = [i for i, b in enumerate(heads) if b is not None]
        if not active:
            return
        if len(active) == 1:  # the others are done: the rest of this one as it comes
            i = active[0]
            head = heads[i]
            assert head is not None
            yield head if at[i] == 0 else head.take(np.arange(at[i], len(head)))
            yield from (b for b in iters[i] if len(b))
            return
        cutoff = min(int(b.times_ns[-1]) for b in heads if b is not None)
        parts: list[Block] = []
        for i in active:
            head = heads[i]
            assert head is not None
            end = at[i] + int(np.searchsorted(head.times_ns[at[i] :], cutoff, side="right"))
            if end > at[i]:
                whole = at[i] == 0 and end == len(head)
                parts.append(head if whole else head.take(np.arange(at[i], end)))
            at[i] = end
            if end == len(head):
                heads[i], at[i] = _next(iters[i]), 0
        if parts:
            yield parts[0] if len(parts) == 1 else joined(parts)


def _next(blocks: Iterator[Block]) -> Block | None:
    for block in blocks:
        if len(block):
            return block
    return None


def joined(parts: Sequence[Block]) -> Block:
    """Blocks (one topic order) as one block in time order: each part's stretch of its buffer copied once."""
    pieces: list[memoryview] = []
    starts: list[np.ndarray] = []
    offset = 0
    for p in parts:
        lo, hi = int(p.starts.min()), int((p.starts + p.lengths).max())
        pieces.append(p.buffer[lo:hi])
        starts.append(p.starts - lo + offset)
        offset += hi - lo
    block = Block(
        np.concatenate([p.times_ns for p in parts]),
        np.concatenate([p.topic_index for p in parts]),
        parts[0].topics,
        memoryview(b"".join(pieces)),
        np.concatenate(starts),
        np.concatenate([p.lengths for p in parts]),
        seq=None
        if all(p.seq is None for p in parts)
        else np.concatenate([np.full(len(p), -1, np.int64) if p.seq is None else p.seq for p in parts]),
        sizes=None if all(p.sizes is None for p in parts) else np.concatenate([p.stored_lengths for p in parts]),
    )
    return in_time_order(block)
