"""Signals during a run: SIGINT, SIGTERM and SIGHUP (a dropped ssh session) end a live run cleanly (the recording
is finalised); SIGTERM and SIGHUP interrupt a batch run like Ctrl-C (its partial file is removed)."""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType


class StopRequested(KeyboardInterrupt):  # a signal, not an error
    """Raised in a batch run by SIGTERM or SIGHUP so the partial file is removed."""


def stoppable() -> None:
    """Ctrl-C stops the app even when its parent ignored SIGINT (``nohup … &``, CI runners: Python then keeps it
    ignored) — the suite and the user send it to stop a run."""
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@contextmanager
def signals_set(stop: threading.Event) -> Iterator[None]:
    """SIGINT, SIGTERM and SIGHUP end a live run cleanly (the recording is finalised)."""

    def handler(signum: int, frame: FrameType | None) -> None:
        stop.set()

    with _handlers(handler):
        yield


@contextmanager
def sigterm_raises() -> Iterator[None]:
    def handler(signum: int, frame: FrameType | None) -> None:
        if _in_finaliser(frame):  # raised there, Python prints it and drops it: the stop would be lost
            threading.Timer(RESEND_S, os.kill, (os.getpid(), signum)).start()
            return
        raise StopRequested

    with _handlers(handler, signals=(signal.SIGTERM, signal.SIGHUP)):
        yield


@contextmanager
def _handlers(
    handler: Callable[[int, FrameType | None], None],
    signals: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP),
) -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():  # tests may run us in a thread
        yield
        return
    # a hangup ignored from the start (``nohup``) stays ignored: the user asked the run to outlive the terminal
    signals = tuple(s for s in signals if s != signal.SIGHUP or signal.getsignal(s) is not signal.SIG_IGN)
    previous = {s: signal.signal(s, handler) for s in signals}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


RESEND_S = 0.05
"""A stop that came during a finaliser is sent again this much later (once the finaliser has returned)."""


def _in_finaliser(frame: FrameType | None) -> bool:
    """Whether the signal came while a ``__del__`` ran (Rerun's ``RecordingStream.__del__`` flushes, wherever the
    garbage collector happens to drop a stream: an exception raised there never reaches the run)."""
    for _ in range(16):
        if frame is None:
            return False
        if frame.f_code.co_name == "__del__":
            return True
        frame = frame.f_back
    return False
