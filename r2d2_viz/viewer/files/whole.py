"""A written ``.rrd`` checked before it is renamed into place, and why a write failed, in one line.

Rerun's file sink writes on its own thread and, when the disk fills, only logs the error (at ``disconnect``) or
says "File-writer thread shut down prematurely": nothing tells the caller. So the file itself is checked: an RRD
stream ends with its footer (rerun 0.41, ``re_log_encoding``): the ``End`` message (kind 0) holding the chunk
manifest, then 32 bytes — u64 offset and u64 length of that message's payload, a u32 checksum, ``RRF2FOOT`` and a
u32 version. A file cut short anywhere lacks them, or they no longer point at an ``End`` message.
"""

from __future__ import annotations

import errno
import os
import resource
import struct
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Protocol

from r2d2_viz.errors import SinkError

FOOTER = struct.Struct("<QQI8sI")
FOOTER_MAGIC = b"RRF2FOOT"
MESSAGE_HEADER = struct.Struct("<QQ")
END_MESSAGE = 0
PROBE_BYTES = 1 << 20
"""How much the probe tries to write after a failed save, to learn the cause (the disk's or the quota's word)."""
FLUSH_SLICE_S = 2.0
"""A flush of a saved file is awaited this long at a time; between slices, whether the file can still grow."""
ROOM_BYTES = 1 << 20
"""Less room than this (a write buffer and then some) and a stalled file counts as full."""
WRITER_DIED = "File-writer thread shut down prematurely"
"""Rerun's RuntimeError when its file sink stopped writing (rerun 0.41)."""


_STUCK: list[object] = []
"""Recording streams whose file sink deadlocked, kept until the process ends (the caller then ends it at once)."""


class Flushable(Protocol):
    def flush(self, *, timeout_sec: float = ...) -> None: ...


def rrd_complete(path: Path) -> bool:
    """Whether ``path`` is a whole RRD stream: it ends with a footer that points at its ``End`` message."""
    try:
        with path.open("rb") as f:
            size = f.seek(0, os.SEEK_END)
            if size < FOOTER.size + MESSAGE_HEADER.size:
                return False
            f.seek(size - FOOTER.size)
            offset, length, _crc, magic, _version = FOOTER.unpack(f.read(FOOTER.size))
            if magic != FOOTER_MAGIC or offset + length + FOOTER.size != size or offset < MESSAGE_HEADER.size:
                return False
            f.seek(offset - MESSAGE_HEADER.size)
            kind, declared = MESSAGE_HEADER.unpack(f.read(MESSAGE_HEADER.size))
            return bool(kind == END_MESSAGE and declared == length)
    except OSError:
        return False


def write_cause(path: Path) -> str:
    """Why writing ``path`` failed, asked of the file system: a probe appended to ``path`` (a partial file, about to
    be removed) is flushed to disk; its error is the cause ("no space left on device", "file too large")."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
        try:
            probe, written = bytes(PROBE_BYTES), 0
            while written < PROBE_BYTES:  # a short write: the next one says why
                written += os.write(fd, probe[written:])
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError as exc:
        return (exc.strerror or errno.errorcode.get(exc.errno or 0, "write error")).lower()
    return "the recording was cut short (no Rerun footer)"


class NotSavedError(SinkError):
    """A save that failed for want of room (or a write error). ``stuck``: Rerun's file sink deadlocked as its writer
    died (rerun 0.41, seen about one run in four on a full disk): its threads then hold the process at exit, so
    the command line ends the process itself once it has said why."""

    def __init__(self, message: str, *, stuck: bool = False) -> None:
        super().__init__(message)
        self.stuck = stuck


class WriterStuckError(RuntimeError):
    """A flush that stalled while its file could not grow."""


def not_saved(target: Path, tmp: Path, *, stuck: bool = False) -> NotSavedError:
    """The one line for a save that failed (``tmp`` removed): the file, the cause, the older file kept."""
    cause = write_cause(tmp)
    tmp.unlink(missing_ok=True)
    kept = "; the older file is untouched" if target.exists() else ""
    return NotSavedError(f"{target}: not saved: {cause}{kept}", stuck=stuck)


def cannot_grow(path: Path) -> bool:
    """Whether ``path`` is at the end of its room: its disk has less than a write buffer free, or it reached the
    process's file size limit (a quota: RLIMIT_FSIZE)."""
    try:
        disk = os.statvfs(path.parent)
        size = path.stat().st_size
    except OSError:
        return True
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    return disk.f_bavail * disk.f_frsize < ROOM_BYTES or (limit != resource.RLIM_INFINITY and size + ROOM_BYTES > limit)


def flush_file(rec: Flushable, path: Path | None) -> None:
    """``rec.flush()`` in slices of ``FLUSH_SLICE_S``: one that stalls while ``path`` cannot grow raises
    :class:`WriterStuckError` instead of waiting for ever (Rerun's file sink can deadlock when its writer dies), as
    does one that says the writer died (the stream's finaliser would then flush it again, and may hang there)."""
    size = -1
    while True:
        try:
            rec.flush(timeout_sec=FLUSH_SLICE_S if path is not None else 1e38)
            return
        except RuntimeError as exc:
            if path is not None and WRITER_DIED in str(exc):  # dead, and dropping the stream may hang as well
                _STUCK.append(rec)
                raise WriterStuckError(str(exc)) from None
            if path is None or "timed out" not in str(exc):
                raise
        grown = path.stat().st_size if path.exists() else -1
        if grown == size and cannot_grow(path):
            _STUCK.append(rec)  # never dropped: its finaliser would flush the deadlocked sink and hang there
            raise WriterStuckError(f"{WRITER_DIED} (stalled)")
        size = grown


def replace_with(tmp: Path, target: Path) -> None:
    """``tmp`` renamed over ``target`` if it is a whole recording; else it is removed and :class:`SinkError` says
    why (``target`` untouched)."""
    if not rrd_complete(tmp):
        raise not_saved(target, tmp)
    os.replace(tmp, target)


@contextmanager
def saved_rrd(tmp: Path | None, target: Path | None) -> Iterator[None]:
    """Around writing ``tmp``: at the end it replaces ``target`` if whole; on any error it is removed, and Rerun's
    "file-writer shut down" becomes the file's one line."""
    if tmp is None or target is None:
        yield
        return
    try:
        yield
    except WriterStuckError:
        raise not_saved(target, tmp, stuck=True) from None
    except (RuntimeError, SinkError) as exc:  # a live run's flush says it as SinkError
        if WRITER_DIED in str(exc):
            raise not_saved(target, tmp) from None
        if not rrd_complete(tmp) and tmp.exists() and cannot_grow(tmp):  # a live flush that timed out on a full disk
            raise not_saved(target, tmp, stuck=True) from None
        tmp.unlink(missing_ok=True)
        raise
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    replace_with(tmp, target)
