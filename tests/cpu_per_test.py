"""Opt-in pytest plugin: the CPU each test costs, beside its wall time (``pytest -p cpu_per_test``).

Wall durations (``--durations``) rank tests by how long they held a worker, which on a shared machine is mostly
the load; the CPU a test spends is what a quiet 2-core run pays for it. Per test (setup, call and teardown): the
worker's own CPU (user + system, all its threads) and that of the child processes it waited for (the CLI run in a
subprocess, a native viewer; a child that outlives the test — the session's Chromium — counts when it is reaped).
The summary lists the slowest by CPU, the CPU of the tests in all, and, for ``R2D2_TEST_CPU_LOG=FILE``, writes one
JSON line a test there.
"""

from __future__ import annotations

import json
import os
import resource
import sys
import time
from collections.abc import Generator
from pathlib import Path

import pytest

SHOWN = 30
_KEY = "cpu_per_test"
_started: dict[str, tuple[float, float, float]] = {}
_rows: list[dict[str, object]] = []


def _cpu() -> tuple[float, float, float]:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    forked = sys.modules.get("forked_cli")  # CLI runs forked from the worker's zygote, which the worker never waits
    extra = float(getattr(forked, "child_cpu", 0.0))
    return own.ru_utime + own.ru_stime, children.ru_utime + children.ru_stime + extra, time.monotonic()


@pytest.hookimpl(hookwrapper=True, tryfirst=True)
def pytest_runtest_setup(item: pytest.Item) -> Generator[None, None, None]:
    _started[item.nodeid] = _cpu()
    yield


@pytest.hookimpl(hookwrapper=True, trylast=True)
def pytest_runtest_teardown(item: pytest.Item) -> Generator[None, None, None]:
    yield
    start = _started.pop(item.nodeid, None)
    if start is not None:  # user_properties travel with the teardown report, from an xdist worker too
        own, children, now = _cpu()
        row = (round(own - start[0], 3), round(children - start[1], 3), round(now - start[2], 3))
        item.user_properties.append((_KEY, row))


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.when != "teardown":
        return
    for key, value in report.user_properties:
        if key == _KEY:
            own, children, wall = value
            _rows.append({"test": report.nodeid, "own": own, "children": children, "wall": wall})


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    if not _rows or os.environ.get("PYTEST_XDIST_WORKER"):
        return
    cpu = {id(row): float(row["own"]) + float(row["children"]) for row in _rows}  # type: ignore[arg-type]
    write = terminalreporter.write_line
    terminalreporter.section(f"slowest {SHOWN} by CPU (own + waited children, s)")
    for row in sorted(_rows, key=lambda r: -cpu[id(r)])[:SHOWN]:
        write(f"{cpu[id(row)]:7.2f} cpu {row['own']:7.2f} own {row['wall']:7.2f} wall  {row['test']}")
    write(f"{sum(cpu.values()):.1f} s of CPU in {len(_rows)} tests (collection and worker start-up not counted)")
    log = os.environ.get("R2D2_TEST_CPU_LOG")
    if log:
        Path(log).write_text("".join(json.dumps(row) + "\n" for row in _rows))
