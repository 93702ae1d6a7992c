"""The recording feed: every follower gets the recording from its first byte (a page opened late, a reload), then
what comes, until the feed closes; what a real Rerun recording stream encodes arrives whole."""

from __future__ import annotations

import re
import subprocess
import sys
import threading
from pathlib import Path

import rerun as rr

from r2d2_viz.viewer.web.feed import RecordingFeed


def test_a_late_follower_gets_everything_from_the_first_byte() -> None:
    pending: list[bytes] = [b"header", b"first"]
    lock = threading.Lock()

    def read() -> bytes:
        with lock:
            data = b"".join(pending)
            pending.clear()
            return data

    feed = RecordingFeed(read, period=0.01)
    early = feed.follow()
    assert next(early) == b"headerfirst"
    with lock:
        pending.append(b"second")
    assert next(early) == b"second"
    late = feed.follow()  # opened after both: both, in order
    assert next(late) + next(late) == b"headerfirstsecond"
    with lock:
        pending.append(b"last")
    feed.close()  # takes what was left, then ends both
    assert list(early) == [b"last"] and list(late) == [b"last"]
    assert feed.size == len(b"headerfirstsecondlast")


def test_a_follower_gone_while_the_feed_is_idle_ends() -> None:
    """Nothing new comes: the follower is asked whether it is gone after each wait, and ends when it is (it held a
    serving place until new bytes failed to reach it)."""
    pending = [b"header"]
    feed = RecordingFeed(lambda: pending.pop() if pending else None, period=0.01)
    asked: list[int] = []

    def gone() -> bool:
        asked.append(1)
        return len(asked) >= 2

    try:
        follower = feed.follow(gone)
        assert next(follower) == b"header"
        assert list(follower) == [] and len(asked) == 2  # ended by its second idle wait, the feed still open
    finally:
        feed.close()


def test_the_history_is_bounded_but_keeps_the_first_read() -> None:
    """Past the history's bytes the oldest reads go, never the first (the recording's identity and layout)."""
    reads = [b"F" * 10]
    feed = RecordingFeed(lambda: reads.pop(0) if reads else None, period=0.01, history=25)
    behind = feed.follow()
    assert next(behind) == b"F" * 10  # it has the first read; then it waits, while the rest comes
    reads.extend([b"a" * 10, b"b" * 10, b"c" * 10])
    while reads:
        threading.Event().wait(0.01)
    feed.close()
    assert feed.size == 20 and list(feed.follow()) == [b"F" * 10, b"c" * 10]
    assert list(behind) == [b"c" * 10]  # "a" and "b" were dropped before it asked again


def test_a_rerun_recording_arrives_whole(tmp_path: Path) -> None:
    """The bytes followed are one RRD stream (a single header, no end marker or footer between the reads: the
    viewer would take each file as a new source and play from the start again) that Rerun's own CLI reads back."""
    rec = rr.RecordingStream("r2d2_viz_feed_test")
    stream = rr.binary_stream(recording=rec)
    feed = RecordingFeed(lambda: stream.read(flush=False), period=0.01)
    for step in range(20):
        rec.set_time("step", sequence=step)
        rec.log("points", rr.Points3D([[step, 0.0, 0.0]]))
        if step % 5 == 4:
            rec.flush()
            threading.Event().wait(0.05)  # the feed takes a read: several RRD files in all
    rec.flush()
    rec.disconnect()
    feed.close()
    rrd = tmp_path / "followed.rrd"
    followed = b"".join(feed.follow())
    rrd.write_bytes(followed)
    assert followed.count(b"RRF2") == 1 and followed.startswith(b"RRF2") and b"RRF2FOOT" not in followed
    rerun = Path(sys.executable).parent / "rerun"
    printed = subprocess.run([str(rerun), "rrd", "print", str(rrd)], capture_output=True, text=True, timeout=60)
    assert printed.returncode == 0, printed.stderr
    assert "/points" in printed.stdout and "Points3D:positions" in printed.stdout
    assert sum(int(n) for n in re.findall(r"with (\d+) rows? .* - /points", printed.stdout)) == 20
