"""The recording as the page's viewer reads it: one RRD byte stream (what ``rr.binary_stream()`` encodes), served
under the page's token at ``recording.rrd`` — Rerun's gRPC server takes no token, so it is not started at all.

Every byte since the start is kept (in memory), so a page opened late, or reloaded, gets the whole recording and
then follows what comes, as it would from Rerun's gRPC server. Pure: the reader is a callable (no rerun here).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator

PUMP_PERIOD_S = 0.05
"""How often the encoded bytes are taken from the recording (the viewer sees data at most this late)."""
WAIT_S = 1.0
"""How long a follower waits for new bytes before it looks again (whether the feed closed)."""

Reader = Callable[[], "bytes | None"]
"""Returns the bytes encoded since its last call (None or b'' if none)."""


class RecordingFeed:
    """RRD bytes from ``read`` (called every :data:`PUMP_PERIOD_S` in a thread of its own), kept for every
    follower: :meth:`follow` yields them all from the first, then the new ones as they come, until :meth:`close`."""

    def __init__(self, read: Reader, period: float = PUMP_PERIOD_S) -> None:
        self._read, self._period = read, period
        self._chunks: list[bytes] = []
        self._changed = threading.Condition()
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._pump, name="r2d2-viz-feed", daemon=True)
        self._thread.start()

    @property
    def size(self) -> int:
        with self._changed:
            return sum(len(c) for c in self._chunks)

    def _take(self) -> None:
        data = self._read()
        if data:
            with self._changed:
                self._chunks.append(bytes(data))
                self._changed.notify_all()

    def _pump(self) -> None:
        while not self._closed.wait(self._period):
            self._take()

    def follow(self) -> Iterator[bytes]:
        """Every chunk from the first; then waits for more (each wait at most :data:`WAIT_S`) until closed."""
        sent = 0
        while True:
            with self._changed:
                if sent == len(self._chunks):
                    if self._closed.is_set():
                        return
                    self._changed.wait(WAIT_S)
                new = self._chunks[sent:]
            sent += len(new)
            yield from new

    def close(self) -> None:
        """Takes the last bytes, then ends every follower (after what it has not yet sent)."""
        if self._closed.is_set():
            return
        self._closed.set()
        self._thread.join(timeout=5)
        self._take()
        with self._changed:
            self._changed.notify_all()
