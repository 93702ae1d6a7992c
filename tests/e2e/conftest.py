"""Fixtures for end-to-end tests that look at the real Rerun viewers (see ``viewers.py``).

A missing prerequisite (Chromium, playwright, Xvfb, Mesa's lavapipe ICD, …) SKIPS the test with
the reason, except when the ``CI`` environment variable is set: then it is a FAILURE, so a broken
CI image cannot silently turn the e2e suite into a row of skips.

Screenshots go to the test's ``tmp_path``, or to ``$E2E_ARTIFACTS_DIR/<test name>/`` when that
variable is set (e.g. for CI to upload them).
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import pytest

from . import viewers

if TYPE_CHECKING:
    from playwright.sync_api import Browser
    from rerun.experimental import ViewerClient


def unavailable(reason: str) -> NoReturn:
    """Skip with ``reason`` — or fail, when running under CI (``CI`` set and non-empty)."""
    if os.environ.get("CI"):
        pytest.fail(f"e2e prerequisite missing under CI: {reason}", pytrace=False)
    pytest.skip(reason)


@pytest.fixture(scope="session")
def chromium_browser() -> Iterator[Browser]:
    """Headless Debian Chromium (playwright), shared by the session; each shot uses a new context."""
    missing = viewers.missing_web_prerequisites()
    if missing:
        unavailable("; ".join(missing))
    from playwright.sync_api import Error as PlaywrightError
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        try:
            browser = viewers.launch_chromium(pw)
        except PlaywrightError as exc:
            unavailable(f"Chromium at {viewers.CHROMIUM_PATH} failed to launch: {exc}")
        try:
            yield browser
        finally:
            browser.close()


@pytest.fixture(scope="session")
def x_display() -> Iterator[viewers.XDisplay]:
    """A private Xvfb server for the native viewer (lavapipe renders; no GPU needed)."""
    missing = viewers.missing_native_prerequisites()
    if missing:
        unavailable("; ".join(missing))
    with contextlib.ExitStack() as stack:
        try:
            display = stack.enter_context(viewers.xvfb())
        except (OSError, RuntimeError) as exc:
            unavailable(f"Xvfb failed to start: {exc}")
        yield display


@pytest.fixture
def artifacts_dir(request: pytest.FixtureRequest, tmp_path: Path) -> Path:
    """Where a test writes its screenshots and viewer logs."""
    root = os.environ.get("E2E_ARTIFACTS_DIR")
    if not root:
        return tmp_path
    path = Path(root) / re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name)
    path.mkdir(parents=True, exist_ok=True)
    return path


@pytest.fixture(scope="session")
def headless_client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ViewerClient]:
    """One windowless native viewer for the session (no display: lavapipe renders), for its views' reports
    (:func:`viewers.view_reports`)."""
    missing = [r for r in viewers.missing_native_prerequisites() if "Xvfb" not in r and "libX11" not in r]
    if missing:
        unavailable("; ".join(missing))
    log = tmp_path_factory.mktemp("headless") / "rerun.log"
    try:
        with viewers.headless_viewer(log) as client:
            yield client
    except (OSError, RuntimeError) as exc:
        unavailable(f"the headless viewer failed to start: {exc}")
