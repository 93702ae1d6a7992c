"""The real CLI on a pseudo-terminal: what a person at a terminal sees (progress bars are drawn only there)."""

from __future__ import annotations

import os
import pty
import subprocess
import sys
import time
from pathlib import Path


def on_a_terminal(*args: str, timeout: float = 180) -> tuple[int, str]:
    """``r2d2-viz ARGS`` with stdin, stdout and stderr on a pseudo-terminal: (exit code, what the terminal showed)."""
    leader, follower = pty.openpty()
    exe = str(Path(sys.executable).parent / "r2d2-viz")
    env = {**os.environ, "COLUMNS": "160", "TERM": "xterm"}
    proc = subprocess.Popen([exe, *args], stdin=follower, stdout=follower, stderr=follower, env=env)
    os.close(follower)
    chunks = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            data = os.read(leader, 65536)
        except OSError:  # the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(leader)
    return proc.wait(timeout=60), b"".join(chunks).decode(errors="replace")
