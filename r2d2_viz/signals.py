"""Signals during a run: SIGINT and SIGTERM end a live run cleanly (the recording is finalised); SIGTERM
interrupts a batch run like Ctrl-C (its partial file is removed)."""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType


class StopRequested(KeyboardInterrupt):  # a signal, not an error
    """Raised in a batch run by SIGTERM so the partial file is removed."""


@contextmanager
def signals_set(stop: threading.Event) -> Iterator[None]:
    """SIGINT and SIGTERM end a live run cleanly (the recording is finalised)."""

    def handler(signum: int, frame: FrameType | None) -> None:
        stop.set()

    with _handlers(handler):
        yield


@contextmanager
def sigterm_raises() -> Iterator[None]:
    def handler(signum: int, frame: FrameType | None) -> None:
        raise StopRequested

    with _handlers(handler, signals=(signal.SIGTERM,)):
        yield


@contextmanager
def _handlers(
    handler: Callable[[int, FrameType | None], None],
    signals: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM),
) -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():  # tests may run us in a thread
        yield
        return
    previous = {s: signal.signal(s, handler) for s in signals}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
