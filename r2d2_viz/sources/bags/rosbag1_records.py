"""The record layer of a ROS 1 bag (rosbag format 2.0, http://wiki.ros.org/Bags/Format/2.0): record headers,
connections, chunks (uncompressed, bz2, or lz4 in the LZ4 frame format rosbag's roslz4 writes), the index at the end
of the file, and the scan that finds the chunks of a bag without one (the index records rosbag writes after each
chunk; the chunk itself where those are missing). Every length is checked against the file's size before it is read.

Pure: no rerun import.
"""

from __future__ import annotations

import bz2
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import BinaryIO

import numpy as np

from r2d2_viz.sources.bags.storage import topic_name

MAGIC = b"#ROSBAG V2.0\n"
OP_MSG, OP_BAG_HEADER, OP_INDEX, OP_CHUNK, OP_CHUNK_INFO, OP_CONNECTION = 2, 3, 4, 5, 6, 7
RENAMED_TYPES = {"tf/msg/tfMessage": "tf2_msgs/msg/TFMessage"}
"""ROS 1 types ROS 2 knows under another name (as ``rosbags-convert`` renames them)."""
_U32, _U64, _TIME = struct.Struct("<I"), struct.Struct("<Q"), struct.Struct("<II")


class BrokenError(Exception):
    """The bytes end or are damaged here."""


def fields(buf: bytes | memoryview, start: int, end: int) -> dict[bytes, bytes]:
    """The ``name=value`` fields of a record header ``buf[start:end]``."""
    out = {}
    while start < end:
        if start + 4 > end:
            raise BrokenError
        (n,) = _U32.unpack_from(buf, start)
        start += 4
        if start + n > end:
            raise BrokenError
        name, sep, value = bytes(buf[start : start + n]).partition(b"=")
        if not sep:
            raise BrokenError
        out[name] = value
        start += n
    return out


def u32(header: dict[bytes, bytes], name: bytes) -> int:
    value = header.get(name, b"")
    if len(value) != 4:
        raise BrokenError
    return int(_U32.unpack(value)[0])


def time_ns(value: bytes) -> int:
    if len(value) != 8:
        raise BrokenError
    sec, nsec = _TIME.unpack(value)
    return int(sec) * 1_000_000_000 + int(nsec)


def ros2_type(ros1_type: str) -> str:
    """``pkg/Type`` → ``pkg/msg/Type`` (with :data:`RENAMED_TYPES`)."""
    pkg, sep, name = ros1_type.rpartition("/")
    full = f"{pkg}/msg/{name}" if sep and "/msg/" not in ros1_type else ros1_type
    return RENAMED_TYPES.get(full, full)


@dataclass
class Connection:
    id: int
    topic: str
    msgtype: str
    definition: str
    md5sum: str


@dataclass
class Chunk:
    pos: int
    start_ns: int
    end_ns: int
    """Receive time of its last message (inclusive)."""
    counts: dict[int, int] = field(default_factory=dict)
    indexed: bool = True
    """Index records (times and offsets of its messages) follow it in the file."""


IndexRows = np.ndarray
"""Rows of (receive time in ns, offset of the message record in the chunk's data), int64, shape (n, 2)."""
_INDEX_ENTRY = np.dtype([("sec", "<u4"), ("nsec", "<u4"), ("offset", "<u4")])


def connection(header: dict[bytes, bytes], data: bytes) -> Connection:
    more = fields(data, 0, len(data))
    text = {k: v.decode("utf-8", "replace") for k, v in more.items()}
    return Connection(
        u32(header, b"conn"),
        topic_name(header.get(b"topic", b"").decode("utf-8", "replace") or text.get(b"topic", "")),
        ros2_type(text.get(b"type", "")),
        text.get(b"message_definition", ""),
        text.get(b"md5sum", ""),
    )


def op_of(header: dict[bytes, bytes]) -> int:
    op = header.get(b"op", b"")
    if len(op) != 1:
        raise BrokenError
    return op[0]


def decompress(compression: bytes, data: bytes, size: int) -> bytes:
    if compression == b"none":
        return data
    if compression == b"bz2":
        return bz2.BZ2Decompressor().decompress(data, max_length=size)
    if compression == b"lz4":
        from lz4.frame import LZ4FrameDecompressor

        return bytes(LZ4FrameDecompressor().decompress(data, max_length=size))
    raise ValueError(f"chunk compression {compression.decode('utf-8', 'replace')!r} is not supported")


def u32_at(buf: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The little-endian uint32 at each offset ``at`` of the bytes ``buf`` (offsets checked by the caller)."""
    b = buf[at[:, None] + np.arange(4)].astype(np.int64)
    return np.asarray(b[:, 0] | (b[:, 1] << 8) | (b[:, 2] << 16) | (b[:, 3] << 24))


def message_spans(buf: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For message records at ``offsets`` of a chunk's bytes ``buf``: where each one's data starts and ends, and
    which of them lie wholly inside ``buf`` (a damaged index may point anywhere)."""
    n = len(buf)
    ok = (offsets >= 0) & (offsets + 8 <= n)
    header_len = np.zeros(len(offsets), dtype=np.int64)
    header_len[ok] = u32_at(buf, offsets[ok])
    data_at = offsets + 4 + header_len
    ok &= data_at + 4 <= n
    data_len = np.zeros(len(offsets), dtype=np.int64)
    data_len[ok] = u32_at(buf, data_at[ok])
    starts = data_at + 4
    ends = starts + data_len
    return starts, ends, ok & (ends <= n)


def chunk_records(buf: bytes) -> Iterator[tuple[dict[bytes, bytes], int, int]]:
    """The records of a chunk's data: header fields, data start, data end; stops at one cut short."""
    pos, n = 0, len(buf)
    while pos + 8 <= n:
        (hl,) = _U32.unpack_from(buf, pos)
        if pos + 8 + hl > n:
            return
        header = fields(buf, pos + 4, pos + 4 + hl)
        (dl,) = _U32.unpack_from(buf, pos + 4 + hl)
        start = pos + 8 + hl
        if start + dl > n:
            return
        yield header, start, start + dl
        pos = start + dl


class RecordFile:
    """The records of an open bag file (of ``size`` bytes), each length checked against that size; ``conns`` and
    ``chunks`` as its index (:meth:`read_index`) or a scan (:meth:`scan`) found them."""

    def __init__(self, bio: BinaryIO, size: int) -> None:
        self.bio, self.size = bio, size
        self.conns: dict[int, Connection] = {}
        self.chunks: list[Chunk] = []

    def _head(self, pos: int) -> tuple[dict[bytes, bytes], bytes, int]:
        """The header fields of the record at ``pos``, its header bytes and data length field, the header length."""
        self.bio.seek(pos)
        head = self.bio.read(4)
        if len(head) < 4:
            raise BrokenError
        (hl,) = _U32.unpack(head)
        if pos + 8 + hl > self.size:
            raise BrokenError
        raw = self.bio.read(hl + 4)
        return fields(raw, 0, hl), raw, hl

    def read(self, pos: int, data: bool = True) -> tuple[dict[bytes, bytes], bytes, int, int]:
        """The record at ``pos``: its header fields, its data (b"" unless ``data``), where its data starts and where
        the next record starts. Raises ``BrokenError`` when it is cut or damaged."""
        header, raw, hl = self._head(pos)
        (dl,) = _U32.unpack_from(raw, hl)
        start = pos + 8 + hl
        if start + dl > self.size:
            raise BrokenError
        body = self.bio.read(dl) if data else b""
        if data and len(body) < dl:
            raise BrokenError
        return header, body, start, start + dl

    def read_index(self, pos: int, conn_count: int, chunk_count: int) -> bool:
        """Reads the connections and chunk infos at ``pos``; False when they are not all there."""
        conns: dict[int, Connection] = {}
        chunks: list[Chunk] = []
        try:
            while len(conns) < conn_count or len(chunks) < chunk_count:
                header, data, _, pos = self.read(pos)
                op = op_of(header)
                if op == OP_CONNECTION:
                    conn = connection(header, data)
                    conns[conn.id] = conn
                elif op == OP_CHUNK_INFO:
                    count = u32(header, b"count")
                    if len(data) < 8 * count:
                        raise BrokenError
                    pairs = struct.unpack_from(f"<{2 * count}I", data)
                    chunks.append(
                        Chunk(
                            int(_U64.unpack(header.get(b"chunk_pos", b""))[0]),
                            time_ns(header.get(b"start_time", b"")),
                            time_ns(header.get(b"end_time", b"")),
                            dict(zip(pairs[0::2], pairs[1::2], strict=True)),
                        )
                    )
                else:
                    raise BrokenError
        except (BrokenError, struct.error, UnicodeDecodeError):
            return False
        self.conns, self.chunks = conns, chunks
        return True

    def scan(self, pos: int) -> int | None:
        """Finds the chunks (and their connections) from ``pos`` on, through the index records after each chunk or,
        where those are missing, the chunk itself; returns where the file breaks off (None: it does not)."""
        chunk: Chunk | None = None
        while pos < self.size:
            try:
                header, data, _, end = self.read(pos, data=False)
                op = op_of(header)
                if op == OP_CHUNK:
                    self._close_scanned(chunk)
                    chunk = Chunk(pos, 0, -1)
                elif op == OP_INDEX and chunk is not None:
                    _, data, _, _ = self.read(pos)
                    conn, count = u32(header, b"conn"), u32(header, b"count")
                    if len(data) < 12 * count:
                        raise BrokenError
                    times = [s * 1_000_000_000 + ns for s, ns, _ in struct.iter_unpack("<III", data[: 12 * count])]
                    if times:
                        chunk.counts[conn] = chunk.counts.get(conn, 0) + count
                        chunk.start_ns = min(times) if chunk.end_ns < 0 else min(chunk.start_ns, *times)
                        chunk.end_ns = max(chunk.end_ns, *times)
                elif op == OP_CONNECTION:
                    _, data, _, _ = self.read(pos)
                    conn_rec = connection(header, data)
                    self.conns.setdefault(conn_rec.id, conn_rec)
                pos = end
            except (BrokenError, struct.error):
                self._close_scanned(chunk)
                self._close_scanned(Chunk(pos, 0, -1))  # a chunk cut short: what there is of it
                return pos
        self._close_scanned(chunk)
        return None

    def _close_scanned(self, chunk: Chunk | None) -> None:
        """Adds a scanned chunk; one without index records after it, or with connections not met yet, is read."""
        if chunk is None:
            return
        if not chunk.counts or any(c not in self.conns for c in chunk.counts):
            try:
                buf = self.chunk_data(chunk.pos, partial=True)
            except (BrokenError, struct.error, ValueError, OSError, EOFError):
                return
            counts: dict[int, int] = {}
            times = []
            for header, start, end in chunk_records(buf):
                op = op_of(header)
                if op == OP_CONNECTION:
                    conn = connection(header, buf[start:end])
                    self.conns.setdefault(conn.id, conn)
                elif op == OP_MSG:
                    c = u32(header, b"conn")
                    counts[c] = counts.get(c, 0) + 1
                    times.append(time_ns(header.get(b"time", b"")))
            if not times:
                return
            chunk.counts, chunk.start_ns, chunk.end_ns = counts, min(times), max(times)
            chunk.indexed = False
        self.chunks.append(chunk)

    def chunk_index(self, chunk: Chunk) -> dict[int, IndexRows] | None:
        """Per connection, the times and offsets of the chunk's messages, from the index records that follow it
        (rosbag writes one per connection after each chunk); None when they are not all there."""
        if not chunk.indexed:
            return None
        try:
            _, _, _, pos = self.read(chunk.pos, data=False)
            out: dict[int, IndexRows] = {}
            for _ in chunk.counts:
                header, data, _, pos = self.read(pos)
                count = u32(header, b"count")
                if op_of(header) != OP_INDEX or len(data) < 12 * count:
                    return None
                entries = np.frombuffer(data, dtype=_INDEX_ENTRY, count=count)
                rows = np.empty((count, 2), dtype=np.int64)
                rows[:, 0] = entries["sec"].astype(np.int64) * 1_000_000_000 + entries["nsec"]
                rows[:, 1] = entries["offset"]
                out[u32(header, b"conn")] = rows
        except (BrokenError, struct.error):
            return None
        return out if set(out) == set(chunk.counts) else None

    def chunk_data(self, pos: int, *, partial: bool = False) -> bytes:
        """The decompressed records of the chunk at ``pos`` (``partial``: what there is of one cut short)."""
        header, raw, hl = self._head(pos)
        if op_of(header) != OP_CHUNK:
            raise BrokenError
        (dl,) = _U32.unpack_from(raw, hl)
        available = self.size - (pos + 8 + hl)
        if dl > available and not partial:
            raise BrokenError
        data = self.bio.read(min(dl, available))
        return decompress(header.get(b"compression", b"none"), data, u32(header, b"size"))
