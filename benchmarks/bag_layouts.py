"""The same sensor bag written the ways users bring it (issue 48), for ``benchmarks/bigbag.py``.

* ``rosbags``: rosbags' writer (MCAP, messages interleaved in time order, a chunk closed past 1 MiB, uncompressed);
* ``rosbag2``: what ``ros2 bag record -s mcap`` writes with no preset: rosbag2_storage_mcap opens
  ``mcap::McapWriterOptions("ros2")`` unchanged (ros2/rosbag2 ``rosbag2_storage_mcap/src/mcap_storage.cpp``), so the
  mcap C++ library's defaults: chunks closed once their uncompressed size reaches ``DefaultChunkSize`` = 768 KiB,
  ``compression = Zstd`` at ``CompressionLevel::Default`` (zstd level 1, ``ZStdCompressionLevel`` in mcap's
  ``writer.inl``), and a chunk that does not get smaller is stored uncompressed (``forceCompression = false``).
  ``rosbag2_zstd`` is exactly that; ``rosbag2`` the same with ``compression: None`` (``--storage-config-file``);
* ``topics``: topic after topic (each topic's messages in time order, then the next topic's), 768 KiB
  uncompressed chunks each of one topic: what a converter that copies connection by connection writes;
* ``db3``: rosbags' SQLite3 writer (one row per message).

Each layout's chunk layout is described by :func:`describe` (from the MCAP summary, through rosbags' reader).
"""

from __future__ import annotations

import itertools
import shutil
import statistics
import sys
import time
from collections.abc import Callable
from io import BytesIO
from pathlib import Path
from typing import ClassVar

LAYOUTS = ("rosbags", "rosbag2", "rosbag2_zstd", "topics", "db3")
ROSBAG2_CHUNK = 1024 * 768
"""mcap C++ ``DefaultChunkSize`` (``mcap/types.hpp``), which rosbag2_storage_mcap leaves as is."""
ROSBAG2_ZSTD_LEVEL = 1
"""mcap C++ ``CompressionLevel::Default`` for zstd."""


def _writer_class(chunk_bytes: int, zstd_level: int | None, topic_chunks: bool) -> type:
    """A rosbags ``Writer`` whose MCAP storage closes chunks at ``chunk_bytes`` (and, ``topic_chunks``, when the
    topic changes), compressing each with zstd at ``zstd_level`` unless that does not make it smaller."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.rosbag2.storage_mcap import McapWriter, write_record, write_uint16, write_uint32, write_uint64

    try:
        from compression import zstd  # type: ignore[import-not-found]
    except ImportError:
        from backports import zstd  # type: ignore[no-redef]

    class Mcap(McapWriter):  # type: ignore[misc]
        last_channel = -1

        def close_chunk(self) -> None:
            raw = self.chunk.bio.getvalue()
            if zstd_level is not None and len(zstd.compress(raw, level=zstd_level)) < len(raw):
                self.compression = "zstd"
                self.compressor = lambda data: zstd.compress(data, level=zstd_level)
            else:
                self.compression, self.compressor = "", lambda data: data
            super().close_chunk()

        def write(self, connection: object, timestamp: int, data: bytes | memoryview) -> None:
            cid = connection.id  # type: ignore[attr-defined]
            if topic_chunks and cid != self.last_channel and self.chunk.bio.tell():
                self.close_chunk()
            self.last_channel = cid
            self.message_start_time = min(timestamp, self.message_start_time)
            self.message_end_time = max(timestamp, self.message_end_time)
            self.channel_stats[cid] += 1
            self.chunk.message_start_time = min(timestamp, self.chunk.message_start_time)
            self.chunk.message_end_time = max(timestamp, self.chunk.message_end_time)
            self.chunk.msgs[cid].append((timestamp, self.chunk.bio.tell()))
            rec = BytesIO()
            write_uint16(rec, cid)
            write_uint32(rec, 0)
            write_uint64(rec, timestamp)
            write_uint64(rec, timestamp)
            rec.write(data)
            write_record(self.chunk.bio, 0x05, rec)
            if self.chunk.bio.tell() >= chunk_bytes:  # mcap C++: once the chunk meets or exceeds chunkSize
                self.close_chunk()

    class LayoutWriter(Writer):  # type: ignore[misc]
        STORAGE_PLUGINS: ClassVar = {**Writer.STORAGE_PLUGINS, StoragePlugin.MCAP: Mcap}

    return LayoutWriter


def write_layout(
    path: Path,
    layout: str,
    events: list[tuple[int, str, int]],
    message: Callable[[str, int, int], bytes | bytearray],
    types: dict[str, str],
    typestore: object,
) -> Path:
    """A rosbag2 directory at ``path`` holding ``events`` (``(log time, topic, index)``, time order) the way
    ``layout`` says; written beside it and moved into place when whole."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    scratch = path.with_name(path.name + ".partial")
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)
    partial = scratch / path.name
    plugin = StoragePlugin.SQLITE3 if layout == "db3" else StoragePlugin.MCAP
    cls: type = Writer
    if layout in ("rosbag2", "rosbag2_zstd", "topics"):
        cls = _writer_class(ROSBAG2_CHUNK, ROSBAG2_ZSTD_LEVEL if layout == "rosbag2_zstd" else None, layout == "topics")
    order = events
    if layout == "topics":
        rank = {topic: i for i, topic in enumerate(types)}
        order = sorted(events, key=lambda e: (rank[e[1]], e[0]))
    with cls(partial, version=9, storage_plugin=plugin) as writer:
        connections = {topic: writer.add_connection(topic, kind, typestore=typestore) for topic, kind in types.items()}
        for t, topic, k in order:
            writer.write(connections[topic], t, message(topic, k, t))
    partial.rename(path)
    scratch.rmdir()
    return path


def layout_bag(folder: Path, *args: object) -> Path:
    """The bag file in ``folder`` (written by :func:`write_layout` with ``args`` if not there yet)."""
    if not folder.exists():
        t = time.perf_counter()
        layout = str(args[0])
        write_layout(folder, layout, *args[1:])  # type: ignore[arg-type]
        print(f"wrote {folder} in {time.perf_counter() - t:.0f} s", file=sys.stderr)
    return next(p for p in folder.iterdir() if p.suffix in (".mcap", ".db3"))


def describe(bag: Path) -> str:
    """The chunk layout of ``bag``: chunks, their median size, compression, topics per chunk, time order."""
    if bag.suffix == ".db3":
        return f".db3: SQLite, one row per message ({bag.stat().st_size / 1e9:.2f} GB)"
    from rosbags.rosbag2.storage_mcap import McapReader

    reader = McapReader(bag)
    reader.open()
    try:
        chunks = list(reader.chunks)  # close() empties the reader's list
        sizes = [c.uncompressed_size for c in chunks]
        kinds = sorted({c.compression or "none" for c in chunks})
        ratio = sum(c.compressed_size for c in chunks) / max(1, sum(sizes))
        topics = statistics.median(len(c.channel_count) for c in chunks)
        overlapping = sum(1 for a, b in itertools.pairwise(chunks) if b.message_start_time < a.message_end_time)
    finally:
        reader.close()
    return (
        f"{len(chunks):,} chunks, median {statistics.median(sizes) / 1024:,.0f} KiB uncompressed, "
        f"{'/'.join(kinds)} (stored {100 * ratio:.0f} % of raw), median {topics:g} topics a chunk, "
        f"{overlapping:,} chunks start before the previous one ends ({bag.stat().st_size / 1e9:.2f} GB)"
    )
