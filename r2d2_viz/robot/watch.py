"""``--watch``: which files make a robot, and a poller that says when they changed (mtime and size, no new
dependency). The clock and the ``stat`` are injected, so tests drive it without sleeping.

A change is reported once the files have stayed the same for ``settle`` seconds (debounce): an editor's
half-written file is not loaded, and a save in several writes is loaded once.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Generic, TypeVar

from r2d2_viz.errors import R2d2VizError
from r2d2_viz.robot.model import MeshFile, Robot

Signature = tuple[int, int] | None
"""A file's (mtime in ns, size), None when it cannot be stat'ed (deleted, or mid-rename)."""
PERIOD_S = 0.25
"""How often the files are looked at."""
SETTLE_S = 0.2
"""How long they must stay unchanged before a reload."""
STOP_WAIT_S = 5.0
"""How long a cancelled load is waited for (its xacro child is killed at once; parsing what came takes no longer)."""
T = TypeVar("T")


def stat_signature(path: Path) -> Signature:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_mtime_ns, st.st_size


def robot_files(description: Path, robot: Robot | None, read: Iterable[Path] = ()) -> tuple[Path, ...]:
    """The description, the files xacro read to make it (``read``), and every mesh file ``robot`` uses — a missing
    one where it would be found, so that it appearing reloads the robot."""
    files = {Path(description).absolute(), *(Path(p).absolute() for p in read)}
    for link in robot.links if robot is not None else ():
        for shape in (*link.visuals, *link.collisions):
            if isinstance(shape.geometry, MeshFile) and shape.geometry.path is not None:
                files.add(Path(shape.geometry.path).absolute())
    files.update(Path(p).absolute() for p in (robot.missing_meshes if robot is not None else ()))
    return tuple(sorted(files))


class FileWatcher:
    """Polls ``files``' signatures; :meth:`changed` is True once after each settled change."""

    def __init__(
        self,
        files: Iterable[Path] = (),
        *,
        stat: Callable[[Path], Signature] = stat_signature,
        clock: Callable[[], float] = time.monotonic,
        period: float = PERIOD_S,
        settle: float = SETTLE_S,
        since_ns: int | None = None,
    ) -> None:
        self.stat, self.clock, self.period, self.settle = stat, clock, period, settle
        self.since_ns = since_ns
        """When the robot was read (wall clock, ns): a file first watched with a later mtime was changed after the
        load and before the watch began (an edit, or a FIFO put in its place, as the run opened its recording), and
        is reported as a change at once."""
        self.files: tuple[Path, ...] = ()
        self._seen: dict[Path, Signature] = {}
        self._pending: dict[Path, Signature] | None = None
        self._pending_since = 0.0
        self._last_poll: float | None = None
        self.watch(files)

    def watch(self, files: Iterable[Path]) -> None:
        """Watch these files from now on (what they are now is the reference for the files not watched yet)."""
        self.files = tuple(files)
        # a file already watched keeps what it was when the change was reported (what the load read): an edit made
        # while the robot was loading is then seen at the next poll
        self._seen = {f: self._seen[f] if f in self._seen else self._first_look(f) for f in self.files}
        self._pending = None

    def _first_look(self, path: Path) -> Signature:
        sig = self.stat(path)
        if sig is not None and self.since_ns is not None and sig[0] > self.since_ns:
            return (-1, -1)  # changed since the robot was read: not what the run shows
        return sig

    def _look(self) -> dict[Path, Signature]:
        return {f: self.stat(f) for f in self.files}

    def changed(self) -> bool:
        """True when a file changed since the last reported change and has since stayed the same for ``settle``
        seconds; looks at most every ``period`` seconds (cheaper calls in between return False)."""
        now = self.clock()
        if self._last_poll is not None and now - self._last_poll < self.period:
            return False
        self._last_poll = now
        current = self._look()
        if current == self._seen:
            self._pending = None
            return False
        if current != self._pending:  # still being written: wait until it stays the same
            self._pending, self._pending_since = current, now
            return False
        if now - self._pending_since < self.settle:
            return False
        self._seen, self._pending = current, None
        return True


class Loading(Generic[T]):
    """One reload's load, in a thread of its own: a live run goes on with the robot it has until :attr:`done`
    (a slow xacro does not freeze it), and :meth:`stop` ends the load at once (its xacro child killed)."""

    def __init__(self, load: Callable[[list[Path], threading.Event], T]) -> None:
        self.cancel = threading.Event()
        self.read: list[Path] = []
        """The files xacro read (even when it failed)."""
        self.result: T | None = None
        self.error: R2d2VizError | None = None
        self._failure: BaseException | None = None
        self._thread = threading.Thread(target=self._run, args=(load,), name="r2d2-viz --watch load", daemon=True)
        self._thread.start()

    def _run(self, load: Callable[[list[Path], threading.Event], T]) -> None:
        try:
            self.result = load(self.read, self.cancel)
        except R2d2VizError as exc:
            self.error = exc
        except BaseException as exc:  # a bug: raised in the run's thread by outcome()
            self._failure = exc

    @property
    def done(self) -> bool:
        return not self._thread.is_alive()

    def outcome(self) -> T:
        """The loaded value once :attr:`done` (waiting for it otherwise); raises the load's error."""
        self._thread.join()
        if self._failure is not None:
            raise self._failure
        if self.error is not None:
            raise self.error
        assert self.result is not None
        return self.result

    def stop(self, timeout: float = STOP_WAIT_S) -> None:
        """Cancel the load (its xacro child is killed) and wait for the thread a little."""
        self.cancel.set()
        self._thread.join(timeout)
