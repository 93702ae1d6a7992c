"""An MCAP file read from the start, chunk by chunk: the fast way to the messages of one topic (rosbags'
reader costs several microseconds a message), and what can be read of a file that breaks off (a recorder that
crashed or was killed leaves no footer and no summary, which ``rosbags`` needs): the records up to the first one
that is incomplete or damaged. MCAP format: https://mcap.dev/spec; lz4 and zstd come with ``rosbags``.

Pure: no rerun import.
"""

from __future__ import annotations

import struct
import sys
import zlib
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import BinaryIO, NamedTuple


def _zstd() -> ModuleType:
    """zstd, imported when a chunk needs it (a run without a bag imports neither codec)."""
    if sys.version_info >= (3, 14):  # pragma: no cover
        from compression import zstd
    else:
        from backports import zstd
    return zstd


MAGIC = b"\x89MCAP0\r\n"
_OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE, _OP_CHUNK, _OP_DATA_END = 0x03, 0x04, 0x05, 0x06, 0x0F
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
_MESSAGE = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time


class _BrokenError(Exception):
    """The file ends or is damaged here."""


def _string(buf: bytes, at: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(buf, at)
    end = at + 4 + n
    if end > len(buf):
        raise _BrokenError
    return buf[at + 4 : end].decode("utf-8", "replace"), end


def _records(bio: BinaryIO, end: int) -> Iterator[tuple[int, bytes]]:
    """Records up to byte ``end`` of ``bio``."""
    while True:
        head = bio.read(9)
        if len(head) < 9:
            return
        op = head[0]
        (size,) = _U64.unpack_from(head, 1)
        if bio.tell() + size > end:
            raise _BrokenError
        body = bio.read(size)
        if len(body) < size:
            raise _BrokenError
        yield op, body


def _chunk_data(body: bytes) -> bytes:
    """The records of a chunk, decompressed and checked."""
    _, _, uncompressed_size, crc = struct.unpack_from("<QQQI", body, 0)
    compression, at = _string(body, 28)
    (size,) = _U64.unpack_from(body, at)
    data = body[at + 8 : at + 8 + size]
    if compression == "lz4":
        from lz4.frame import decompress as lz4_decompress

        data = lz4_decompress(data)
    elif compression == "zstd":
        data = _zstd().decompress(data)
    elif compression:
        raise _BrokenError
    if len(data) != uncompressed_size or (crc and zlib.crc32(data) != crc):
        raise _BrokenError
    return data


class _Channel(NamedTuple):
    id: int
    topic: str
    msgtype: str


class McapScan:
    """An MCAP file read from the start, record by record: fast for ROS 2 bags (whose recorder writes the
    messages in the order it received them), and the way to read a damaged one up to its damage."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.channels: dict[int, _Channel] = {}

    def topics(self) -> dict[str, tuple[str, int]]:
        """topic → (message type, messages found): one scan of the whole file."""
        counts: dict[int, int] = {}
        for channel_id, _ in self._scan(None):
            counts[channel_id] = counts.get(channel_id, 0) + 1
        topics: dict[str, tuple[str, int]] = {}
        for channel in self.channels.values():
            old = topics.get(channel.topic, (channel.msgtype, 0))
            topics[channel.topic] = (channel.msgtype, old[1] + counts.get(channel.id, 0))
        return topics

    def messages(self, topic: str) -> Iterator[tuple[int, memoryview]]:
        """``(log time, data)`` of the messages on ``topic``, in file order."""
        return self._scan(topic)  # type: ignore[return-value]

    def _scan(self, topic: str | None) -> Iterator[tuple[int, memoryview] | tuple[int, int]]:
        """With a ``topic``, ``(log time, data)`` of its messages in file order, until the file breaks off;
        without, ``(channel id, log time)`` of every message. Fills :attr:`channels` on the way."""
        schemas: dict[int, str] = {}
        wanted: set[int] = set()
        unpack, head, skip = _U64.unpack_from, _MESSAGE.unpack_from, _MESSAGE.size
        with self.path.open("rb") as bio:
            if bio.read(8) != MAGIC:
                return
            try:
                for op, body in _records(bio, self.path.stat().st_size):
                    if op == _OP_DATA_END:  # the summary follows: indexes, no more messages
                        return
                    data = _chunk_data(body) if op == _OP_CHUNK else bytes([op]) + _U64.pack(len(body)) + body
                    view, at, end = memoryview(data), 0, len(data)
                    while at < end:
                        op2, (size,) = data[at], unpack(data, at + 1)
                        start, at = at + 9, at + 9 + size
                        if at > end:
                            raise _BrokenError
                        if op2 == _OP_MESSAGE:
                            channel_id, _, log_time, _ = head(data, start)
                            if channel_id in wanted:
                                yield log_time, view[start + skip : at]
                            elif topic is None:
                                yield channel_id, log_time
                        elif op2 == _OP_CHANNEL:
                            channel_id, schema_id = struct.unpack_from("<HH", data, start)
                            name = _string(data, start + 4)[0]
                            self.channels[channel_id] = _Channel(channel_id, name, schemas.get(schema_id, ""))
                            if name == topic:
                                wanted.add(channel_id)
                        elif op2 == _OP_SCHEMA:
                            (schema_id,) = _U16.unpack_from(data, start)
                            schemas[schema_id] = _string(data, start + 2)[0]
            except (
                _BrokenError,
                struct.error,
                RuntimeError,
                ValueError,
                OverflowError,
                MemoryError,
                _zstd().ZstdError,
            ):
                return  # the rest of the file is missing or damaged
