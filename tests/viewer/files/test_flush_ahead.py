"""A batch run's non-draining backpressure (issue 48): a mark waits only for the flush the previous mark started,
and starts its own in a helper thread; a flush's error comes out at the next mark; the block's end waits for the
last. Flushes here block on events the test sets (no clock): a mark that waited for its own flush would hang the
test at the first ``assert``, and the ``wait`` bounds are only there so that a broken build fails instead."""

from __future__ import annotations

import threading

import pytest

from r2d2_viz.viewer.files.flush_ahead import FlushAhead

BOUND_S = 60.0


class _Flushes:
    """A flush per call that returns when the test releases it; what it saw when it started."""

    def __init__(self) -> None:
        self.started: list[threading.Event] = []
        self.release: list[threading.Event] = []
        self.done = 0
        self.error: BaseException | None = None

    def __call__(self) -> None:
        release = threading.Event()
        self.release.append(release)
        self.started[len(self.release) - 1].set()
        assert release.wait(BOUND_S)
        self.done += 1
        if self.error is not None:
            raise self.error

    def expect(self) -> threading.Event:
        self.started.append(threading.Event())
        return self.started[-1]


def test_a_mark_starts_a_flush_and_returns_and_the_next_mark_waits_for_it() -> None:
    flushes = _Flushes()
    ahead = FlushAhead(flushes)
    first = flushes.expect()
    ahead()  # returns while the flush is held: the run goes on preparing the next mark's data
    assert first.wait(BOUND_S) and flushes.done == 0 and ahead.marks == 1
    second = flushes.expect()
    marked = threading.Thread(target=ahead)  # the next mark: it must wait for the first flush
    marked.start()
    marked.join(0.2)  # a bound on a wait that must not end, not a time measured
    assert marked.is_alive() and not second.is_set()  # waiting: the first flush has not returned
    flushes.release[0].set()
    assert second.wait(BOUND_S) and flushes.done == 1  # the first returned before the second started
    marked.join(BOUND_S)
    flushes.release[1].set()
    ahead.wait()
    assert flushes.done == 2 and ahead.marks == 2


def test_a_flushs_error_comes_out_at_the_next_mark_and_the_block_waits_for_the_last() -> None:
    flushes = _Flushes()
    flushes.error = OSError("no space left on device")
    with pytest.raises(OSError, match="no space"), FlushAhead(flushes) as ahead:
        flushes.expect()
        ahead()
        flushes.release[0].set()
        flushes.expect()
        ahead()  # the previous flush failed: raised here, in the run's thread; no new flush
    assert flushes.done == 1 and ahead.marks == 1
    flushes = _Flushes()
    with FlushAhead(flushes) as ahead:
        flushes.expect()
        ahead()
        flushes.release[0].set()
    assert flushes.done == 1  # the block's end waited for it


def test_a_run_that_fails_waits_for_the_flush_in_flight_and_keeps_its_own_error() -> None:
    flushes = _Flushes()
    flushes.error = OSError("the flush's")
    with pytest.raises(KeyboardInterrupt), FlushAhead(flushes) as ahead:
        flushes.expect()
        ahead()
        flushes.release[0].set()
        raise KeyboardInterrupt
    assert flushes.done == 1
