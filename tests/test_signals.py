"""SIGINT/SIGTERM during a run: a live run stops cleanly, a batch run is interrupted; handlers restored."""

from __future__ import annotations

import os
import signal
import threading

import pytest

from r2d2_viz.signals import StopRequested, signals_set, sigterm_raises


def test_a_live_run_sees_the_signal_as_a_stop_and_the_old_handlers_come_back() -> None:
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    for signum in (signal.SIGINT, signal.SIGTERM):
        stop = threading.Event()
        with signals_set(stop):
            os.kill(os.getpid(), signum)
        assert stop.is_set()
    assert {s: signal.getsignal(s) for s in before} == before


def test_sigterm_interrupts_a_batch_run_like_ctrl_c() -> None:
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(StopRequested), sigterm_raises():
        os.kill(os.getpid(), signal.SIGTERM)
        signal.sigtimedwait([], 0.1)  # the handler runs at the next bytecode boundary
    assert issubclass(StopRequested, KeyboardInterrupt)  # the CLI's Ctrl-C path: exit 130, partial file removed
    assert signal.getsignal(signal.SIGTERM) == before
