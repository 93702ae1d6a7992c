"""Processes the app starts die with it (Linux's parent-death signal), however the app ends: a parent that starts a
child with :func:`dies_with` and is then killed (SIGKILL: no handler of its own runs) takes the child along."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

PARENT = """
import os, subprocess, sys
from r2d2_viz.robot.children import dies_with
me = os.getpid()
child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"], preexec_fn=lambda: dies_with(me))
print(child.pid, flush=True)
time.sleep(120)
"""


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the parent-death signal is Linux's")
def test_a_child_gets_sigterm_when_its_parent_is_killed() -> None:
    parent = subprocess.Popen([sys.executable, "-c", "import time\n" + PARENT], stdout=subprocess.PIPE, text=True)
    assert parent.stdout is not None
    child = int(parent.stdout.readline())
    assert _alive(child)
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait(10)
    deadline = time.monotonic() + 10
    while _alive(child) and time.monotonic() < deadline:
        time.sleep(0.02)
    still = _alive(child)
    if still:  # not left behind by the test
        os.kill(child, signal.SIGKILL)
    assert not still
