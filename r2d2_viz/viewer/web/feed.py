"""The recording as the page's viewer reads it: one RRD byte stream (what ``rr.binary_stream()`` encodes), served
under the page's token at ``recording.rrd`` — Rerun's gRPC server takes no token, so it is not started at all.

The bytes since the start are kept in memory, so a page opened late, or reloaded, gets the whole recording and then
follows what comes, as from Rerun's gRPC server; like it, at most :data:`HISTORY_BYTES` (its default, 1 GiB): past
that the oldest data goes, but never the first bytes read (the recording's identity, its layout and the robot's
meshes, sent when it opens). Each read is a whole RRD stream, so what is dropped is whole too. Pure: the reader is
a callable (no rerun here).

Each read of a binary stream is whole RRD files (header, messages, end marker, footer). Concatenated, the viewer
takes each as a new source and plays the recording from its start again; so the feed is *one* stream: the first
header, then the messages of every file (:func:`messages`), never an end (a live stream's).
"""

from __future__ import annotations

import struct
import threading
from collections.abc import Callable, Iterator

PUMP_PERIOD_S = 0.05
"""How often the encoded bytes are taken from the recording (the viewer sees data at most this late)."""
HISTORY_BYTES = 1 << 30
WAIT_S = 1.0
"""How long a follower waits for new bytes before it looks again (whether the feed closed)."""

MAGIC = b"RRF2"
HEADER_BYTES = 12
"""An RRD stream's header: ``RRF2``, the format version, the options (compression)."""
MESSAGE_HEAD = struct.Struct("<QQ")
"""Each message: its kind (0: the end of the stream, its payload the footer) and its length in bytes."""
TRAILER = b"RRF2FOOT"
TRAILER_BYTES = 32
"""After the end marker's footer: where the footer is, a checksum, ``RRF2FOOT`` and its version."""

Reader = Callable[[], "bytes | None"]
"""Returns the bytes encoded since its last call (None or b'' if none)."""


def messages(rrd: bytes) -> tuple[bytes, bytes]:
    """The header of the first of the RRD files in ``rrd`` and the messages of all of them, without their end
    markers and footers; ``(b"", rrd)`` if they are not laid out as expected (then passed on whole)."""
    header, body, offset = b"", [], 0
    while offset < len(rrd):
        if rrd[offset : offset + 4] != MAGIC or offset + HEADER_BYTES > len(rrd):
            return b"", rrd
        header = header or rrd[offset : offset + HEADER_BYTES]
        start = offset = offset + HEADER_BYTES
        while True:
            if offset + MESSAGE_HEAD.size > len(rrd):
                return b"", rrd
            kind, length = MESSAGE_HEAD.unpack_from(rrd, offset)
            if kind == 0:
                break
            offset += MESSAGE_HEAD.size + length
        body.append(rrd[start:offset])
        offset += MESSAGE_HEAD.size + length + TRAILER_BYTES
        if rrd[offset - 12 : offset - 4] != TRAILER:
            return b"", rrd
    return header, b"".join(body)


class RecordingFeed:
    """RRD bytes from ``read`` (called every :data:`PUMP_PERIOD_S` in a thread of its own), kept for every
    follower: :meth:`follow` yields them all from the first, then the new ones as they come, until :meth:`close`."""

    def __init__(self, read: Reader, period: float = PUMP_PERIOD_S, history: int = HISTORY_BYTES) -> None:
        self._read, self._period, self._history = read, period, history
        self._chunks: list[bytes] = []  # the first read, then the newest that fit in the history
        self._dropped = 0  # reads dropped (after the first) to keep within the history
        self._size = 0
        self._changed = threading.Condition()
        self._stopping = threading.Event()  # the pump stops…
        self._closed = threading.Event()  # …then, once the last bytes are kept, the followers end
        self._thread = threading.Thread(target=self._pump, name="r2d2-viz-feed", daemon=True)
        self._thread.start()

    @property
    def size(self) -> int:
        """Bytes kept."""
        with self._changed:
            return self._size

    def _take(self) -> None:
        data = self._read()
        if data:
            header, body = messages(bytes(data))
            data = header + body if not self._chunks or not header else body
            with self._changed:
                self._chunks.append(data)
                self._size += len(data)
                while self._size > self._history and len(self._chunks) > 2:  # the oldest but the first
                    self._size -= len(self._chunks.pop(1))
                    self._dropped += 1
                self._changed.notify_all()

    def _pump(self) -> None:
        while not self._stopping.wait(self._period):
            self._take()

    def follow(self, gone: Callable[[], bool] = lambda: False) -> Iterator[bytes]:
        """Every chunk kept, from the first; then the new ones as they come (each wait at most :data:`WAIT_S`)
        until closed, or until ``gone()`` says the follower is (asked after each wait that brought nothing: a
        follower that left an idle recording must not hold its place until new bytes fail to reach it). A follower
        that fell behind what was dropped goes on from the oldest kept."""
        sent = 0  # reads yielded or skipped, dropped ones included
        while True:
            with self._changed:
                if sent == self._dropped + len(self._chunks):
                    if self._closed.is_set():
                        return
                    self._changed.wait(WAIT_S)
                    if sent == self._dropped + len(self._chunks) and gone():
                        return
                new = self._chunks[max(sent - self._dropped, 1) if sent else 0 :]
                sent = self._dropped + len(self._chunks)
            yield from new

    def close(self) -> None:
        """Takes the last bytes, then ends every follower (after what it has not yet sent)."""
        if self._stopping.is_set():
            return
        self._stopping.set()
        self._thread.join(timeout=5)
        self._take()  # (a follower that saw the feed closed before these bytes were kept would never send them)
        with self._changed:
            self._closed.set()
            self._changed.notify_all()
