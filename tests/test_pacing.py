"""Live pacing on the wall clock: robot samples and feed items (recorded TF, display messages) each sent when due,
in time order, never early; checked against a simulated clock (no test waits for or measures real time, so a busy
machine cannot fail them) and stand-ins that note when each send happened."""

from __future__ import annotations

import numpy as np

from r2d2_viz.pacing import WallClock, paced
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.sources.base import ArraySource, SampleChunk
from r2d2_viz.sources.playback import Window, source_windows


class _SimClock:
    """Simulated time: ``sleep`` moves it on by what was asked plus ``oversleep`` (a busy machine wakes late)."""

    def __init__(self, oversleep: float = 0.0) -> None:
        self.t = 1000.0
        self.oversleep = oversleep
        self.sleeps = 0

    def now(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        assert seconds > 0
        self.sleeps += 1
        self.t += seconds + self.oversleep

    @property
    def wall(self) -> WallClock:
        return WallClock(now=self.now, sleep=self.sleep)


class _Recorder:
    """A stand-in for RobotStream that notes when (on the simulated clock) each run of samples was sent."""

    class _Rec:
        def flush(self) -> None:
            pass

    def __init__(self, clock: _SimClock) -> None:
        self.clock = clock
        self.rec = self._Rec()
        self.sent: list[tuple[float, int, int]] = []

    def prepare(self, chunk):
        return chunk

    def send(self, chunk, start: int, stop: int) -> None:
        self.sent.append((self.clock.now(), int(chunk.times_ns[start]), stop - start))


class _NoFeeds:
    next_time_ns = None
    sent = 0

    def push(self, window: Window) -> None:
        assert not window.displays and window.tf is None

    def until(self, time_ns) -> None:
        pass


class _Items:
    """A stand-in for Feeds: the display messages of each window pushed; notes the clock when each is handed on."""

    def __init__(self, clock: _SimClock) -> None:
        self.clock = clock
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
            self.at.append((self.clock.now(), self.next_time_ns))


class _Bar:
    """A stand-in for the progress bar: the windows done and each position it was told, in order."""

    def __init__(self) -> None:
        self.windows: list[Window] = []
        self.positions: list[int] = []

    def __call__(self, window: Window) -> None:
        self.windows.append(window)
        self.positions.append(window.end_ns)

    def at(self, t_ns: int) -> None:
        self.positions.append(t_ns)


MS = 1_000_000


def _samples(*ms: int) -> SampleChunk:
    return SampleChunk(np.array(ms, dtype=np.int64) * MS, ("j",), np.zeros((len(ms), 1)))


def _messages(*ms: int) -> tuple[TopicMessage, ...]:
    return tuple(TopicMessage(t * MS, "/chatter", "std_msgs/msg/String", b"") for t in ms)


def test_paced_samples_go_out_in_order_and_not_before_they_are_due() -> None:
    n, period = 12, 0.02
    times = (np.arange(n) * period * 1e9).astype(np.int64)
    source = ArraySource(times, ["j"], np.zeros((n, 1)))
    clock = _SimClock()
    streamer = _Recorder(clock)
    seen = _Bar()
    windows = list(source_windows(source, 5))
    sent, stopped = paced(streamer, windows, _NoFeeds(), speed=2.0, progress=seen, wall=clock.wall)
    assert sent == n and not stopped and seen.windows == windows and len(windows) == 3
    # twice as fast: sample k is due k * 10 ms after the first; a clock that wakes on time sends each alone, on time
    first = streamer.sent[0][0]
    assert [k for _, _, k in streamer.sent] == [1] * n
    assert [t for _, t, _ in streamer.sent] == list(times)
    assert np.allclose([wall - first for wall, _, _ in streamer.sent], np.arange(n) * period / 2.0, atol=1e-9)


def test_a_late_wake_up_sends_what_is_due_at_once_without_shifting_the_schedule() -> None:
    # every sleep wakes 25 ms late (a loaded machine), samples 10 ms apart: the samples due by then go out
    # together, none early, and the schedule does not drift (the last goes out within one oversleep of its time)
    n, period = 30, 0.01
    times = (np.arange(n) * period * 1e9).astype(np.int64)
    clock = _SimClock(oversleep=0.025)
    streamer = _Recorder(clock)
    sent, stopped = paced(
        streamer, list(source_windows(ArraySource(times, ["j"], np.zeros((n, 1))), 7)), _NoFeeds(), wall=clock.wall
    )
    assert sent == n and not stopped
    assert sum(k for _, _, k in streamer.sent) == n and max(k for _, _, k in streamer.sent) > 1
    first = streamer.sent[0][0]
    for wall, t_ns, k in streamer.sent:
        last_due = t_ns * 1e-9 + (k - 1) * period  # the run's last sample
        assert wall - first >= last_due - 1e-9  # never early
        assert wall - first <= t_ns * 1e-9 + 0.025 + 1e-9  # its first sample at most one oversleep late
    assert streamer.sent[-1][0] - first <= (n - 1) * period + 0.025 + 1e-9


def test_feed_items_between_samples_go_out_at_their_own_time_and_after_the_last_sample() -> None:
    # samples at 0, 100, 200 ms; items at 30, 60, 130 ms and 350 ms (after the robot's last sample), read in three
    # windows as a bag's pass hands them on
    windows = [
        Window(100 * MS, joints=_samples(0, 100), displays=_messages(30, 60)),
        Window(200 * MS, joints=_samples(200), displays=_messages(130)),
        Window(350 * MS, displays=_messages(350)),
    ]
    clock = _SimClock()
    streamer, items = _Recorder(clock), _Items(clock)
    sent, stopped = paced(streamer, windows, items, wall=clock.wall)
    assert sent == 3 and not stopped and items.sent == 4
    first = streamer.sent[0][0]
    assert [(round((wall - first) * 1e3, 6), t_ns // MS) for wall, t_ns, _ in streamer.sent] == [
        (0, 0),
        (100, 100),
        (200, 200),
    ]
    # each item at its own time, not batched with the sample after it
    assert [(round((wall - first) * 1e3, 6), t_ns // MS) for wall, t_ns in items.at] == [
        (30, 30),
        (60, 60),
        (130, 130),
        (350, 350),
    ]


def test_without_a_robot_the_items_keep_their_schedule() -> None:
    clock = _SimClock()
    items = _Items(clock)
    windows = [Window(40 * MS, displays=_messages(0, 40)), Window(80 * MS, displays=_messages(80))]
    sent, stopped = paced(None, windows, items, speed=2.0, wall=clock.wall)  # twice as fast: 0, 20, 40 ms
    assert sent == 3 and not stopped
    first = items.at[0][0]
    assert [round((wall - first) * 1e3, 6) for wall, _ in items.at] == [0, 20, 40]


def test_pacing_sleeps_in_short_steps_so_a_signal_is_seen_soon() -> None:
    # one item 2 s after another: the wait is cut into sleeps of at most MAX_SLEEP (0.1 s) each
    clock = _SimClock()
    asked: list[float] = []
    wall = WallClock(now=clock.now, sleep=lambda s: (asked.append(s), clock.sleep(s)) and None)
    items = _Items(clock)
    paced(None, [Window(2000 * MS, displays=_messages(0, 2000))], items, wall=wall)
    assert [t for _, t in items.at] == [0, 2000 * MS] and len(asked) >= 20 and max(asked) <= 0.1


def test_the_bar_moves_as_a_window_plays_not_when_it_ends() -> None:
    # one window of 20 s of bag time (a small bag is one window), a message a second, at 1x: the bar is told where
    # the replay is at every wait (at most MAX_SLEEP, 0.1 s, of bag time apart), up to the window's end
    clock = _SimClock()
    bar = _Bar()
    window = Window(20_000 * MS, displays=_messages(*range(0, 20_001, 1000)))
    paced(None, [window], _Items(clock), wall=clock.wall, progress=bar)
    steps = np.diff(bar.positions)
    assert bar.positions[-1] == 20_000 * MS and (steps >= 0).all()
    assert max(steps) <= 100 * MS + 1 and len(bar.positions) > 190  # 20 s in steps of at most 0.1 s


def test_a_stopped_replay_shows_where_it_stopped() -> None:
    # Ctrl-C 7.5 s into a 20 s window: the bar stays at 7.5 s (it showed the window's end, 100 %, before)
    import threading

    clock = _SimClock()
    stop = threading.Event()

    def sleep(seconds: float) -> None:
        clock.sleep(seconds)
        if clock.t >= 1000.0 + 7.5:
            stop.set()  # what the SIGINT handler does

    bar = _Bar()
    window = Window(20_000 * MS, displays=_messages(*range(0, 20_001, 1000)))
    _, stopped = paced(None, [window], _Items(clock), wall=WallClock(clock.now, sleep), progress=bar, stop=stop)
    assert stopped and bar.windows == []
    assert abs(bar.positions[-1] - 7_500 * MS) <= 100 * MS and max(bar.positions) == bar.positions[-1]
