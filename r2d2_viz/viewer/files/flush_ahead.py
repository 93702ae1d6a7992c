"""A batch run's backpressure that does not drain the writer (issue 48).

A batch run marks every ``FLUSH_BYTES`` handed to Rerun. Flushing at each mark and waiting left Rerun's file writer
idle while the run waited, and the run idle while the writer wrote (12.6 % of the main thread in ``flush``). Here
each mark waits only for the flush started at the *previous* mark, then starts the next in a helper thread: the
writer always has the last mark's data to write while the run prepares the next, and at most two marks' worth is
ever in flight (memory stays bounded, as before).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from types import TracebackType

FLUSH_BYTES = 64 << 20
"""A batch run marks every this much data (bag bytes, and the Arrow bytes of robot samples): at a mark it waits for
the sinks to have taken what came before the previous mark."""


class FlushAhead:
    """``flush`` run in a helper thread at each mark (``ahead()``), after the previous mark's flush has returned.

    An error of a flush (a full disk: :class:`~r2d2_viz.viewer.files.whole.WriterStuckError`) is raised at the
    next mark or at :meth:`wait`; leaving the ``with`` block waits for the last flush."""

    def __init__(self, flush: Callable[[], None]) -> None:
        self._flush = flush
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None
        self.marks = 0
        """Flushes started (tests read it)."""

    def __call__(self) -> None:
        """A mark: wait for the flush the previous mark started, then start this one's."""
        self.wait()
        self.marks += 1
        self._thread = threading.Thread(target=self._run, name="r2d2-viz flush", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            self._flush()
        except BaseException as exc:  # raised in the run's thread, at its next mark
            self._error = exc

    def wait(self) -> None:
        """Until the flush in flight has returned; its error, if it had one."""
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        error, self._error = self._error, None
        if error is not None:
            raise error

    def __enter__(self) -> FlushAhead:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        if kind is None:
            self.wait()
        elif self._thread is not None:  # already failing: the flush's own error would only hide this one
            self._thread.join()
            self._thread, self._error = None, None
