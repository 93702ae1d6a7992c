"""A small output file (``--tf-tree FILE.dot`` / ``.svg``) written whole, as ``--save`` writes a recording
(:mod:`.whole`): into a hidden partial beside the target (``.NAME.PID.partial``: the same file system, so the
rename is atomic), flushed to disk, then renamed over the target. The partial is made anew (``O_EXCL``, which
refuses any existing name, a symlink included) and a target that is a symlink is replaced, never written through
(the file it points at is untouched). A write that fails (a full disk) removes the partial and says why in one
line; the older file, if any, is untouched."""

from __future__ import annotations

import errno
import os
from pathlib import Path

from r2d2_viz.errors import SinkError


class NotWrittenError(SinkError):
    """An output file that could not be written: ``FILE: not written: no space left on device``."""


def cause(exc: OSError) -> str:
    """The file system's word for a failed write, as ``ls`` or ``cp`` print it ("no space left on device")."""
    return (exc.strerror or errno.errorcode.get(exc.errno or 0, "write error")).lower()


def partial_of(target: Path) -> Path:
    """The hidden partial beside ``target``."""
    return target.with_name(f".{target.name}.{os.getpid()}.partial")


def check_target(target: Path) -> None:
    """Whether ``target`` can be written, asked before any work that leads to it: :class:`NotWrittenError` for a
    missing directory, a directory in the target's place, or a directory where no file can be made (its partial,
    made and removed at once, says why: "permission denied", "read-only file system")."""
    parent = target.parent
    if not parent.is_dir():
        raise NotWrittenError(f"{target}: not written: no such directory {str(parent)!r}")
    if target.is_dir():
        raise NotWrittenError(f"{target}: not written: is a directory")
    tmp = partial_of(target)
    try:
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600))
    except OSError as exc:
        raise NotWrittenError(f"{target}: not written: {cause(exc)}") from None
    tmp.unlink()


def write_whole(target: Path, data: bytes) -> None:
    """``data`` as the file ``target``, whole or not at all (:class:`NotWrittenError`: the partial removed, an older
    ``target`` untouched)."""
    check_target(target)
    tmp = partial_of(target)
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
    except OSError as exc:
        raise NotWrittenError(f"{target}: not written: {cause(exc)}") from None
    try:
        try:
            view, written = memoryview(data), 0
            while written < len(data):  # a short write: the next one says why
                written += os.write(fd, view[written:])
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, target)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise NotWrittenError(f"{target}: not written: {cause(exc)}") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
