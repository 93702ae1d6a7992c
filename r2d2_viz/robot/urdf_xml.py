"""Safe XML for robot descriptions: a small, well-formed, UTF-8 document free of entity declarations.

``read_urdf_xml`` (a file) and ``parse_urdf_xml`` (text) return the ``<robot>`` element or raise
:class:`UrdfError` with one line: no "billion laughs", no XXE — nothing referenced by the document is
ever read. :mod:`r2d2_viz.robot.urdf_check` then checks the robot it describes.
"""

from __future__ import annotations

import re
import stat
from pathlib import Path
from typing import NoReturn

from lxml import etree

from r2d2_viz.errors import UrdfError
from r2d2_viz.robot.regular_file import NotRegularFileError, read_regular

MAX_FILE_BYTES = 64 * 1024 * 1024
# XML 1.0 forbids these characters; refusing them up front also stops UTF-16 look-alikes.
_BAD_CHARS = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")
_POSITION_SUFFIX = re.compile(r",\s*line \d+, column \d+\s*\Z")


def _q(value: str, limit: int = 60) -> str:
    """Quote a value from the file for a message: never multi-line, never huge."""
    if len(value) > limit:
        value = value[: limit // 2] + "…" + value[-(limit // 2) :]
    return repr(value)


def _one_line(text: str) -> str:
    return " ".join(part.strip() for part in text.splitlines() if part.strip())


def _fail(source: str, *parts: str) -> NoReturn:
    raise UrdfError(_one_line(": ".join((source, *parts))))


# --------------------------------------------------------------------------- safe XML


def read_urdf_xml(path: Path) -> etree._Element:
    """Read and strictly parse a URDF file; return the <robot> root element (comments stripped)
    or raise UrdfError.

    Comments and processing instructions are removed; the file's path is recorded as the
    document URL so that ``check_robot`` resolves relative mesh paths against its directory.
    """
    path = Path(path)
    name = _one_line(path.name or str(path)) or repr(str(path))
    try:
        st = path.stat()
    except FileNotFoundError:
        _fail(name, f"file not found ({_q(str(path), 200)})")
    except OSError as exc:
        _fail(name, f"cannot access file: {exc.strerror or exc}")
    if stat.S_ISDIR(st.st_mode):
        _fail(name, "is a directory, not a URDF file")
    if not stat.S_ISREG(st.st_mode):
        _fail(name, "is not a regular file")
    if st.st_size > MAX_FILE_BYTES:
        _fail(name, f"file is too large ({st.st_size} bytes; the limit is {MAX_FILE_BYTES} bytes)")
    try:
        data = read_regular(path, MAX_FILE_BYTES)  # never a FIFO put there since the stat: its open would block
    except NotRegularFileError:
        _fail(name, "is not a regular file")
    except OSError as exc:
        _fail(name, f"cannot read file: {exc.strerror or exc}")
    if len(data) > MAX_FILE_BYTES:
        _fail(name, f"file is too large (more than {MAX_FILE_BYTES} bytes)")
    return _parse_bytes(data, name, str(path.absolute()))


def parse_urdf_xml(text: str | bytes, *, source: str, base_dir: Path) -> etree._Element:
    """:func:`read_urdf_xml` for a description given as text; ``source`` names it in messages and
    ``base_dir`` is where its relative mesh paths resolve."""
    data = text.encode("utf-8") if isinstance(text, str) else bytes(text)
    name = _one_line(source) or "robot_description"
    if len(data) > MAX_FILE_BYTES:
        _fail(name, f"description is too large ({len(data)} bytes; the limit is {MAX_FILE_BYTES} bytes)")
    return _parse_bytes(data, name, str(Path(base_dir).absolute() / "robot_description.urdf"))


def _parse_bytes(data: bytes, name: str, url: str) -> etree._Element:
    if not data.strip():
        _fail(name, "file is empty")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        _fail(name, f"line {line}: not valid UTF-8 (byte 0x{data[exc.start]:02x} at offset {exc.start})")
    bad = _BAD_CHARS.search(text)
    if bad:
        line = text.count("\n", 0, bad.start()) + 1
        _fail(name, f"line {line}: character U+{ord(bad.group()):04X} is not allowed in XML")
    # Refuse entity declarations before the parser sees them: nothing gets expanded or fetched.
    if "<!DOCTYPE" in text and "<!ENTITY" in text:
        _fail(name, "DOCTYPE declares entities (<!ENTITY ...>); refused for safety: URDF needs no entities")
    parser = etree.XMLParser(
        encoding="utf-8",  # what was checked above, whatever the XML declaration claims
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        dtd_validation=False,
        attribute_defaults=False,
        huge_tree=False,
        recover=False,
        remove_comments=True,
        remove_pis=True,
    )
    try:
        root = etree.fromstring(data, parser, base_url=url)
    except etree.XMLSyntaxError as exc:
        msg = _POSITION_SUFFIX.sub("", _one_line(str(exc.msg or exc)))
        line = exc.position[0] if exc.position else 0
        _fail(name, f"line {line}: not well-formed XML: {msg}")
    if root is None:
        _fail(name, "not well-formed XML: no root element")
    for node in root.iter(etree.Entity):
        _fail(name, f"entity reference {_q(str(node.text))} is not allowed (entities are refused for safety)")
    if root.tag != "robot":
        _fail(name, f"root element is <{_q(str(root.tag), 80)[1:-1]}>; expected <robot>")
    return root
