"""What can be read of an MCAP file that breaks off: a recorder that crashed or was killed leaves no footer and
no summary, which ``rosbags`` needs; this reads the records from the start instead, up to the first one that
is incomplete or damaged (MCAP format: https://mcap.dev/spec; lz4 and zstd come with ``rosbags``).

Pure: no rerun import.
"""

from __future__ import annotations

import struct
import sys
import zlib
from collections.abc import Iterator
from io import BytesIO
from pathlib import Path
from typing import BinaryIO, NamedTuple

from lz4.frame import decompress as lz4_decompress

if sys.version_info >= (3, 14):  # pragma: no cover
    from compression import zstd
else:
    from backports import zstd

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


def _chunk_records(body: bytes) -> Iterator[tuple[int, bytes]]:
    _, _, uncompressed_size, crc = struct.unpack_from("<QQQI", body, 0)
    compression, at = _string(body, 28)
    (size,) = _U64.unpack_from(body, at)
    data = body[at + 8 : at + 8 + size]
    if compression == "lz4":
        data = lz4_decompress(data)
    elif compression == "zstd":
        data = zstd.decompress(data)
    elif compression:
        raise _BrokenError
    if len(data) != uncompressed_size or (crc and zlib.crc32(data) != crc):
        raise _BrokenError
    yield from _records(BytesIO(data), len(data))


class _Channel(NamedTuple):
    id: int
    topic: str
    msgtype: str


class _Message(NamedTuple):
    channel: int
    log_time: int
    data: bytes


class RecoveredMcap:
    """The messages of a damaged MCAP file, found by one scan at construction (:attr:`topics`) and read by
    another (:meth:`messages`)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.topics: dict[str, tuple[str, int]] = {}
        """topic → (message type, messages recovered)."""
        counts: dict[int, int] = {}
        channels: dict[int, _Channel] = {}
        for record in self._scan():
            if isinstance(record, _Channel):
                channels[record.id] = record
            else:
                counts[record.channel] = counts.get(record.channel, 0) + 1
        for channel in channels.values():
            old = self.topics.get(channel.topic, (channel.msgtype, 0))
            self.topics[channel.topic] = (channel.msgtype, old[1] + counts.get(channel.id, 0))

    def _scan(self) -> Iterator[_Channel | _Message]:
        """Channels and messages in file order, until the file breaks off."""
        schemas: dict[int, str] = {}
        with self.path.open("rb") as bio:
            if bio.read(8) != MAGIC:
                return
            try:
                for op, body in _records(bio, self.path.stat().st_size):
                    if op == _OP_DATA_END:  # the summary follows: indexes, no more messages
                        return
                    inner = _chunk_records(body) if op == _OP_CHUNK else iter([(op, body)])
                    for op2, body2 in inner:
                        if op2 == _OP_SCHEMA:
                            (schema_id,) = _U16.unpack_from(body2, 0)
                            schemas[schema_id] = _string(body2, 2)[0]
                        elif op2 == _OP_CHANNEL:
                            channel_id, schema_id = struct.unpack_from("<HH", body2, 0)
                            yield _Channel(channel_id, _string(body2, 4)[0], schemas.get(schema_id, ""))
                        elif op2 == _OP_MESSAGE:
                            channel_id, _, log_time, _ = _MESSAGE.unpack_from(body2, 0)
                            yield _Message(channel_id, log_time, body2[_MESSAGE.size :])
            except (_BrokenError, struct.error, RuntimeError, ValueError, OverflowError, MemoryError, zstd.ZstdError):
                return  # the rest of the file is missing or damaged

    def messages(self, topic: str) -> Iterator[tuple[int, bytes]]:
        """``(log time, data)`` of the recovered messages on ``topic``, in file order."""
        wanted: set[int] = set()
        for record in self._scan():
            if isinstance(record, _Channel):
                if record.topic == topic:
                    wanted.add(record.id)
            elif record.channel in wanted:
                yield record.log_time, record.data
