"""Child processes that end with the app: Linux's parent-death signal, for every process the app starts (the xacro
sandbox, ``--dataset --serve``'s web viewer, a fleet's workers), so none outlives it, however the app ends
(SIGKILL included; elsewhere than Linux, nothing)."""

from __future__ import annotations

import ctypes
import os
import signal
import sys

PR_SET_PDEATHSIG = 1
_PRCTL = ctypes.CDLL(None).prctl if sys.platform.startswith("linux") else None
"""Looked up before any fork: a ``preexec_fn`` should do as little as it can."""


def die_with_parent() -> None:
    """SIGTERM to this process when the one that started it ends (Linux's parent-death signal; elsewhere nothing).

    The signal comes when the *thread* that started the child ends: start it from a thread that outlives it."""
    if _PRCTL is not None:
        _PRCTL(PR_SET_PDEATHSIG, signal.SIGTERM)


def dies_with(parent: int) -> None:
    """:func:`die_with_parent`, and at once if ``parent`` (the starter's pid, read before the fork) already ended
    before the child could ask (the signal is not sent for a parent that died earlier)."""
    die_with_parent()
    if _PRCTL is not None and os.getppid() != parent:
        os.kill(os.getpid(), signal.SIGTERM)
