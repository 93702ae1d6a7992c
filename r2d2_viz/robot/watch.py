"""``--watch``: which files make a robot, and a poller that says when they changed (mtime and size, no new
dependency). The clock and the ``stat`` are injected, so tests drive it without sleeping.

A change is reported once the files have stayed the same for ``settle`` seconds (debounce): an editor's
half-written file is not loaded, and a save in several writes is loaded once.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterable
from pathlib import Path

from r2d2_viz.robot.model import MeshFile, Robot

Signature = tuple[int, int] | None
"""A file's (mtime in ns, size), None when it cannot be stat'ed (deleted, or mid-rename)."""
PERIOD_S = 0.25
"""How often the files are looked at."""
SETTLE_S = 0.2
"""How long they must stay unchanged before a reload."""


def stat_signature(path: Path) -> Signature:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_mtime_ns, st.st_size


def robot_files(description: Path, robot: Robot | None, read: Iterable[Path] = ()) -> tuple[Path, ...]:
    """The description, the files xacro read to make it (``read``), and every mesh file ``robot`` uses."""
    files = {Path(description).absolute(), *(Path(p).absolute() for p in read)}
    for link in robot.links if robot is not None else ():
        for shape in (*link.visuals, *link.collisions):
            if isinstance(shape.geometry, MeshFile) and shape.geometry.path is not None:
                files.add(Path(shape.geometry.path).absolute())
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
    ) -> None:
        self.stat, self.clock, self.period, self.settle = stat, clock, period, settle
        self.files: tuple[Path, ...] = ()
        self._seen: dict[Path, Signature] = {}
        self._pending: dict[Path, Signature] | None = None
        self._pending_since = 0.0
        self._last_poll: float | None = None
        self.watch(files)

    def watch(self, files: Iterable[Path]) -> None:
        """Watch these files from now on (what they are now is the reference)."""
        self.files = tuple(files)
        self._seen = self._look()
        self._pending = None

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
