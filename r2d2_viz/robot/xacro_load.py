"""Robot descriptions as ROS users keep them: a URDF, or a xacro file expanded with the PyPI ``xacro`` package.

:func:`load_robot` (and :func:`load_description`, the URDF text alone) reads a file and, when it is xacro
(``.xacro`` or a xacro namespace), expands it in a child process (:mod:`r2d2_viz.robot.xacro_sandbox`) with a
wall-clock timeout, CPU and memory limits and a bound on the output, so a hostile file can neither hang
nor exhaust the app, and its expressions cannot reach Python's insides (see that module).

What a xacro file can still read: files it includes or loads (``xacro:include``, ``xacro.load_yaml``), by
any path the user can read, and environment variables (``$(env NAME)``, ``$(optenv NAME)``).
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import stat
import subprocess
import sys
import threading
import time
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

from lxml import etree

from r2d2_viz.errors import UrdfError, UsageError, XacroError
from r2d2_viz.robot.children import dies_with
from r2d2_viz.robot.packages import PackageIndex
from r2d2_viz.robot.regular_file import NotRegularFileError, read_regular
from r2d2_viz.robot.urdf_xml import MAX_FILE_BYTES
from r2d2_viz.robot.xacro_sandbox import MEMORY_BYTES

if TYPE_CHECKING:
    from r2d2_viz.robot.model import Robot

TIMEOUT_S = 60.0
"""Wall-clock and CPU time a xacro expansion may take."""
CANCEL_POLL_S = 0.05
"""How often an expansion that can be cancelled looks whether it was."""
_XACRO_NS = re.compile(
    rb"""xmlns:[A-Za-z_][\w.-]*\s*=\s*["']https?://(?:www\.|wiki\.)?ros\.org/(?:wiki/)?xacro/?["']"""
)


class Description(NamedTuple):
    """A robot description ready for :func:`r2d2_viz.robot.model.parse_urdf`."""

    text: bytes
    """The URDF (expanded if the file was xacro), UTF-8."""
    source: str
    """The file's name, for messages."""
    base_dir: Path
    """Where relative mesh paths resolve: the file's folder."""
    warnings: tuple[str, ...] = ()
    """xacro's own warnings (one line each)."""
    files: tuple[Path, ...] = ()
    """The files xacro read besides the description: includes, YAML it loaded (``--watch`` watches them)."""


def load_description(
    path: str | Path,
    *,
    mappings: Mapping[str, str] | None = None,
    packages: PackageIndex | None = None,
    read: list[Path] | None = None,
    cancel: threading.Event | None = None,
) -> Description:
    """Read ``path``; expand it if it is xacro (``NAME:=VALUE`` arguments in ``mappings``; ``$(find)``
    through ``packages``). Raises :class:`UrdfError` (:class:`XacroError` for xacro problems). ``read`` gets
    the files xacro read, even when it fails (``--watch``); setting ``cancel`` stops xacro at once
    (:class:`XacroCancelledError`)."""
    path = Path(path)
    data = read_bounded(path)
    if not is_xacro(path, data):
        return Description(data, path.name, path.parent)
    packages = packages or PackageIndex.from_environ(description=path)
    files: list[Path] = [] if read is None else read
    text, notes = _expand(path, mappings or {}, packages, files, cancel)
    return Description(text.encode("utf-8"), path.name, path.parent, notes, tuple(files))


def load_robot(
    path: str | Path,
    *,
    mappings: Mapping[str, str] | None = None,
    packages: PackageIndex | None = None,
    read: list[Path] | None = None,
    cancel: threading.Event | None = None,
) -> Robot:
    """A :class:`~r2d2_viz.robot.model.Robot` from a URDF or xacro file (xacro's warnings first in its warnings).
    ``NAME:=VALUE`` ``mappings`` are for xacro files only (:class:`UsageError` otherwise). ``read`` gets the
    files xacro read (includes, YAML), even when it fails; ``cancel``: as for :func:`load_description`."""
    from r2d2_viz.robot.model import load_urdf, parse_urdf

    path = Path(path)
    packages = packages or PackageIndex.from_environ(description=path)
    if not is_xacro(path, _peek(path)):
        if mappings:
            raise UsageError(f"{', '.join(f'{k}:={v}' for k, v in mappings.items())}: arguments for a xacro file, "
                             f"but {path.name} is not one")  # fmt: skip
        return load_urdf(path, packages=packages)  # its own one-line errors for unreadable files
    description = load_description(path, mappings=mappings, packages=packages, read=read, cancel=cancel)
    try:
        robot = parse_urdf(
            description.text, source=description.source, base_dir=description.base_dir, packages=packages
        )
    except UrdfError as exc:
        if str(exc).endswith("has no <link> elements"):  # e.g. a file of macros, meant to be included
            raise UrdfError(f"{exc} after xacro (does it only define macros that another file calls?)") from None
        raise
    return dataclasses.replace(robot, warnings=description.warnings + robot.warnings)


def _peek(path: Path) -> bytes:
    """The file's bytes up to the size limit; nothing if it cannot be read (:func:`load_urdf` then says why)."""
    try:
        return read_regular(path, MAX_FILE_BYTES)
    except OSError:
        return b""


def expand_xacro(path: str | Path, *, mappings: Mapping[str, str], packages: PackageIndex) -> str:
    """The URDF a xacro file expands to (hardened, in a child process). Raises :class:`XacroError`."""
    return _expand(Path(path), mappings, packages)[0]


def is_xacro(path: Path, data: bytes) -> bool:
    """By extension, or a xacro namespace declaration (``xmlns:xacro="http://www.ros.org/wiki/xacro"``) in a
    file that uses xacro: many URDFs made by xacro keep the declaration and nothing else (they load as they
    are, without a xacro run)."""
    if path.suffix.lower() == ".xacro":
        return True
    found = _XACRO_NS.search(data[:65536])
    return found is not None and _uses_xacro(data)


def _uses_xacro(data: bytes) -> bool:
    """A xacro element, or ``${`` / ``$(`` in an attribute or text (comments aside). Unparsable: False (the
    URDF reader then says what is wrong)."""
    parser = etree.XMLParser(
        resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False, remove_comments=True, remove_pis=True
    )
    try:
        root = etree.fromstring(data, parser)
    except (etree.XMLSyntaxError, ValueError):
        return False
    xacro_uris = {uri for uri in root.nsmap.values() if uri and "xacro" in uri}
    for el in root.iter():
        if not isinstance(el.tag, str):
            continue
        if el.tag.startswith("{") and el.tag[1:].split("}")[0] in xacro_uris:
            return True
        texts = [el.text or "", el.tail or "", *el.attrib.values()]
        if any("${" in t or "$(" in t for t in texts):
            return True
    return False


def read_bounded(path: Path) -> bytes:
    """A regular file's bytes, refused (one line) when missing, special or over the size limit."""
    name = path.name or str(path)
    try:
        st = path.stat()
    except FileNotFoundError:
        raise UrdfError(f"{name}: file not found ({str(path)!r})") from None
    except OSError as exc:
        raise UrdfError(f"{name}: cannot access file: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise UrdfError(f"{name}: is a directory, not a URDF file")
    if not stat.S_ISREG(st.st_mode):
        raise UrdfError(f"{name}: is not a regular file")
    try:
        data = read_regular(path, MAX_FILE_BYTES)  # never a FIFO put there since the stat: its open would block
    except NotRegularFileError:
        raise UrdfError(f"{name}: is not a regular file") from None
    except OSError as exc:
        raise UrdfError(f"{name}: cannot read file: {exc.strerror or exc}") from None
    if len(data) > MAX_FILE_BYTES:
        raise UrdfError(f"{name}: file is too large (more than {MAX_FILE_BYTES} bytes)")
    return data


# --------------------------------------------------------------------------- the parent side


def _expand(
    path: Path,
    mappings: Mapping[str, str],
    packages: PackageIndex,
    read: list[Path] | None = None,
    cancel: threading.Event | None = None,
) -> tuple[str, tuple[str, ...]]:
    job = {
        "path": str(path.absolute()),
        "mappings": dict(mappings),
        "pins": {k: str(v) for k, v in packages.pins.items()},
        "paths": [str(p) for p in packages.paths],
        "description": str(packages.description) if packages.description is not None else str(path.absolute()),
        "ros_package_path": [str(p) for p in packages.ros_package_path],
        "ament_prefix_path": [str(p) for p in packages.ament_prefix_path],
        "cpu_seconds": TIMEOUT_S + 5,  # the CPU limit only backs up the wall clock, which names the problem
    }
    done = _sandboxed(json.dumps(job), path, cancel)
    try:
        answer = json.loads(done.stdout)
    except ValueError:
        why = _last_line(done.stderr) or f"exit status {done.returncode}"
        if done.returncode < 0 or "MemoryError" in done.stderr:
            why = f"xacro ran out of its limits (memory {MEMORY_BYTES >> 20} MiB, CPU {TIMEOUT_S:g} s)"
        raise XacroError(f"{path.name}: xacro expansion failed: {why}") from None
    if read is not None:
        read.extend(Path(f) for f in answer.get("files", ()) if Path(f) != path.absolute())
    if "error" in answer:
        raise XacroError(str(answer["error"]))
    return str(answer["urdf"]), tuple(str(w) for w in answer.get("warnings", ()))


def _sandboxed(job: str, path: Path, cancel: threading.Event | None) -> subprocess.CompletedProcess[str]:
    """The sandbox run on ``job``: it gets SIGTERM if the app ends first (however it ends), and SIGKILL once
    ``cancel`` is set (a ``--watch`` reload the run no longer waits for), after :data:`TIMEOUT_S`, or on Ctrl-C."""
    parent = os.getpid()
    child = subprocess.Popen(
        [sys.executable, "-m", "r2d2_viz.robot.xacro_sandbox"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: dies_with(parent),
    )
    end = time.monotonic() + TIMEOUT_S
    sent: str | None = job  # given once: a retried communicate() goes on writing what is left
    try:
        while True:
            try:
                out, err = child.communicate(sent, timeout=CANCEL_POLL_S if cancel is not None else TIMEOUT_S)
                return subprocess.CompletedProcess(child.args, child.returncode, out, err)
            except subprocess.TimeoutExpired:
                sent = None
                if cancel is not None and cancel.is_set():
                    raise XacroCancelledError(f"{path.name}: xacro expansion cancelled") from None
                if time.monotonic() >= end:
                    raise XacroError(f"{path.name}: xacro expansion took more than {TIMEOUT_S:g} s; stopped") from None
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()  # reaped, its pipes closed


class XacroCancelledError(XacroError):
    """An expansion stopped because its ``cancel`` event was set (nobody waits for it any more)."""


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1][:300] if lines else ""
