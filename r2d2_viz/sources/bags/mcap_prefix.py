"""How much of a compressed MCAP chunk the wanted messages need: a chunk is decompressed only up to the end of its
last wanted message, found from the chunk's message indexes (every channel's: the next message's offset bounds the
last wanted one). A few small topics of a bag whose chunks each end in a camera frame then decompress a tenth of
it. The chunk's CRC covers all of it, so a chunk read in part is not checked against it (zstd and lz4 frames still
fail on damaged data). Pure: no rerun import.
"""

from __future__ import annotations

import mmap

import numpy as np

from r2d2_viz.sources.bags.mcap_records import (
    OP_MESSAGE_INDEX,
    U32,
    BrokenError,
    ChunkIndex,
    _zstd,
    chunk_record,
)


def wanted_end(buf: mmap.mmap, c: ChunkIndex, wanted: dict[int, int], lo: int, hi: int) -> int | None:
    """The offset in the uncompressed chunk where its last wanted message received in ``[lo, hi)`` ends, bounded by
    the next message of any channel; None: the whole chunk (no usable index, or nothing after it)."""
    if not c.index_offsets:
        return None
    last, every = -1, []
    for channel_id, at in c.index_offsets.items():
        if at + 15 > len(buf) or buf[at] != OP_MESSAGE_INDEX:
            return None
        (n,) = U32.unpack_from(buf, at + 11)
        if at + 15 + n > len(buf) or n % 16:
            return None
        pairs = np.frombuffer(buf, dtype="<u8", count=n // 8, offset=at + 15).reshape(-1, 2)
        every.append(pairs[:, 1])
        if channel_id in wanted:
            inside = pairs[(pairs[:, 0] >= max(lo, 0)) & (pairs[:, 0] < hi), 1]
            if len(inside):
                last = max(last, int(inside.max()))
    if last < 0 or not every:
        return None
    offsets = np.concatenate(every)
    after = offsets[offsets > last]
    return int(after.min()) if len(after) else None


def chunk_prefix(buf: mmap.mmap, start: int, end: int, upto: int) -> memoryview | None:
    """The first ``upto`` bytes of a compressed chunk record's messages (None: the chunk is not compressed, or
    ``upto`` is not less than its size — read it whole)."""
    uncompressed_size, _, compression, raw = chunk_record(buf, start, end)
    if not compression or upto >= uncompressed_size:
        return None
    if compression == "zstd":
        data: bytes = _zstd().ZstdDecompressor().decompress(raw, max_length=upto)
    elif compression == "lz4":
        from lz4.frame import LZ4FrameDecompressor

        data = LZ4FrameDecompressor().decompress(raw, max_length=upto)
    else:
        return None  # chunk_data says what is wrong with it
    if len(data) != upto:
        raise BrokenError("a chunk's size is not what it says")
    return memoryview(data)


def wanted_part(buf: mmap.mmap, c: ChunkIndex, wanted: dict[int, int], lo: int, hi: int) -> memoryview | None:
    """The part of a compressed chunk up to its last wanted message (None: read it whole)."""
    end = wanted_end(buf, c, wanted, lo, hi)
    return None if end is None else chunk_prefix(buf, c.offset, c.offset + c.length, end)
