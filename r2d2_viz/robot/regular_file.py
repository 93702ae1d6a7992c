"""Reading a file the user named only when it is a regular file: a FIFO, a device or a socket is never opened.

``open()`` of a FIFO blocks until a writer comes, and a signal does not end that wait (Python retries the call):
a description replaced by a FIFO under ``--watch`` held the app for good. So the file is opened with
``O_NONBLOCK`` (a FIFO then opens at once, a device without waiting for a carrier) and checked with ``fstat`` on
the descriptor before a byte is read (no race between a check and the open).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path


class NotRegularFileError(OSError):
    """The path names a directory, a FIFO, a device or a socket."""


def read_regular(path: str | Path, limit: int) -> bytes:
    """At most ``limit + 1`` bytes of ``path`` (one more than ``limit`` says it is larger), only when it is a regular
    file. Raises :class:`NotRegularFileError` (``IsADirectoryError`` for a directory) or the ``OSError`` of the
    open or read."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    with open(fd, "rb", buffering=0, closefd=True) as f:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise IsADirectoryError(f"{path}: is a directory")
        if not stat.S_ISREG(st.st_mode):
            raise NotRegularFileError(f"{path}: is not a regular file")
        want = min(limit + 1, max(st.st_size, 0) + 1)  # one allocation of the file's size (a mesh: not twice)
        data = f.read(want) or b""
        if len(data) == want and want < limit + 1:  # it grew since fstat
            data += f.read(limit + 1 - want) or b""
        return data
