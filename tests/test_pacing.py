"""Live pacing on the wall clock: robot samples and feed items (recorded TF, display messages) each sent when due,
in time order, never early; checked with the monotonic clock and stand-ins that note when each send happened."""

from __future__ import annotations

import time

import numpy as np

from r2d2_viz.pacing import paced
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.sources.base import ArraySource, SampleChunk
from r2d2_viz.sources.playback import Window, source_windows


class _Recorder:
    """A stand-in for RobotStream that notes when each run of samples was sent."""

    class _Rec:
        def flush(self) -> None:
            pass

    def __init__(self) -> None:
        self.rec = self._Rec()
        self.sent: list[tuple[float, int, int]] = []

    def prepare(self, chunk):
        return chunk

    def send(self, chunk, start: int, stop: int) -> None:
        self.sent.append((time.monotonic(), int(chunk.times_ns[start]), stop - start))


class _NoFeeds:
    next_time_ns = None
    sent = 0

    def push(self, window: Window) -> None:
        assert not window.displays and window.tf is None

    def until(self, time_ns) -> None:
        pass


class _Items:
    """A stand-in for Feeds: the display messages of each window pushed; notes the wall clock when each is handed
    on."""

    def __init__(self) -> None:
        self.times: list[int] = []
        self.at: list[tuple[float, int]] = []

    def push(self, window: Window) -> None:
        self.times += [m.time_ns for m in window.displays]

    @property
    def next_time_ns(self):
        return self.times[len(self.at)] if len(self.at) < len(self.times) else None

    @property
    def sent(self) -> int:
        return len(self.at)

    def until(self, time_ns) -> None:
        while self.next_time_ns is not None and (time_ns is None or self.next_time_ns <= time_ns):
            self.at.append((time.monotonic(), self.next_time_ns))


MS = 1_000_000


def _samples(*ms: int) -> SampleChunk:
    return SampleChunk(np.array(ms, dtype=np.int64) * MS, ("j",), np.zeros((len(ms), 1)))


def _messages(*ms: int) -> tuple[TopicMessage, ...]:
    return tuple(TopicMessage(t * MS, "/chatter", "std_msgs/msg/String", b"") for t in ms)


def test_paced_samples_go_out_in_order_and_not_before_they_are_due() -> None:
    n, period = 12, 0.02
    times = (np.arange(n) * period * 1e9).astype(np.int64)
    source = ArraySource(times, ["j"], np.zeros((n, 1)))
    streamer = _Recorder()
    start = time.monotonic()
    seen: list[Window] = []
    windows = list(source_windows(source, 5))
    sent, stopped = paced(streamer, windows, _NoFeeds(), speed=2.0, progress=seen.append)  # twice as fast: 10 ms apart
    assert sent == n and not stopped and seen == windows and len(windows) == 3
    assert sum(k for _, _, k in streamer.sent) == n
    assert [t for _, t, _ in streamer.sent] == sorted(t for _, t, _ in streamer.sent)
    first = streamer.sent[0][0]
    for wall, t_ns, _ in streamer.sent:
        assert wall - first >= t_ns * 1e-9 / 2.0 - 1e-3  # never early (1 ms of clock granularity)
    assert time.monotonic() - start >= (n - 1) * period / 2.0 - 1e-3


def test_feed_items_between_samples_go_out_at_their_own_time_and_after_the_last_sample() -> None:
    # samples at 0, 100, 200 ms; items at 30, 60, 130 ms and 350 ms (after the robot's last sample), read in three
    # windows as a bag's pass hands them on
    windows = [
        Window(100 * MS, joints=_samples(0, 100), displays=_messages(30, 60)),
        Window(200 * MS, joints=_samples(200), displays=_messages(130)),
        Window(350 * MS, displays=_messages(350)),
    ]
    streamer, items = _Recorder(), _Items()
    sent, stopped = paced(streamer, windows, items)
    assert sent == 3 and not stopped and items.sent == 4
    first = streamer.sent[0][0]
    for wall, t_ns in items.at:
        offset = wall - first
        assert t_ns * 1e-9 - 1e-3 <= offset < t_ns * 1e-9 + 0.05, (t_ns, offset)  # due, not batched with a sample


def test_without_a_robot_the_items_keep_their_schedule() -> None:
    items = _Items()
    windows = [Window(40 * MS, displays=_messages(0, 40)), Window(80 * MS, displays=_messages(80))]
    sent, stopped = paced(None, windows, items, speed=2.0)  # twice as fast: 0, 20, 40 ms
    assert sent == 3 and not stopped
    first = items.at[0][0]
    assert [round((wall - first) * 1000 / 10) for wall, _ in items.at] == [0, 2, 4]  # in 10 ms steps
