"""ROS packages without ROS: the one resolver for ``$(find pkg)`` (xacro) and ``package://`` (meshes).

A package is a folder holding a ``package.xml``; it is found by the ``<name>`` inside that file, not by the
folder's name (a clone named ``Universal_Robots_ROS2_Description`` holds the package ``ur_description``).
:class:`PackageIndex` looks, in this order:

1. ``--package-path NAME=DIR`` pins;
2. above the description: the enclosing package (walking up to a ``package.xml``), its siblings in the
   same repository or workspace (the folders around it, a few levels deep), and an enclosing install
   prefix's ament index (``<prefix>/share/ament_index/resource_index/packages/<name>``);
3. ``--package-path DIR`` entries (a package, a folder of packages, or an install prefix);
4. ``ROS_PACKAGE_PATH`` (folders of packages), then ``AMENT_PREFIX_PATH`` (install prefixes);
5. last resort, what r2d2-viz did before: a folder above the description named like the package.

Scans are bounded (depth, folder count), skip hidden folders and ``COLCON_IGNORE``/``CATKIN_IGNORE``/
``AMENT_IGNORE`` folders, and read each ``package.xml`` with a parser that fetches and expands nothing.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from urllib.parse import unquote, urlsplit

from lxml import etree

from r2d2_viz.errors import SHOWN, PackageError, UsageError, listed
from r2d2_viz.robot.regular_file import read_regular

SCAN_DEPTH = 3
"""How deep a folder of packages is searched for ``package.xml`` files."""
SCAN_MAX_DIRS = 20_000
"""Folders visited per scanned root at most: a ``--package-path ~`` stays fast."""
WALK_UP_MAX = 64
MAX_PACKAGE_XML_BYTES = 1024 * 1024
_IGNORE_MARKERS = ("COLCON_IGNORE", "CATKIN_IGNORE", "AMENT_IGNORE")
_PACKAGE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*\Z")
_PARSER = etree.XMLParser(
    resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False, remove_comments=True
)


def package_xml_name(folder: Path) -> str | None:
    """The ``<name>`` declared by ``folder/package.xml``, or None (no file, unreadable, malformed)."""
    try:
        data = read_regular(folder / "package.xml", MAX_PACKAGE_XML_BYTES)
        if len(data) > MAX_PACKAGE_XML_BYTES or b"<!ENTITY" in data:
            return None
        root = etree.fromstring(data, _PARSER)
    except (OSError, ValueError, etree.XMLSyntaxError):
        return None
    if root is None or root.tag != "package":
        return None
    name = root.find("name")
    text = (name.text or "").strip() if name is not None else ""
    return text or None


def _is_dir(path: Path) -> bool:
    try:
        return path.is_dir()
    except (OSError, ValueError):
        return False


def _is_file(path: Path) -> bool:
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False


def scan_packages(root: Path, *, depth: int = SCAN_DEPTH) -> dict[str, Path]:
    """Packages in ``root`` (itself a package, or folders of packages down to ``depth`` levels), by name;
    the first one found wins, as with rospack. A package's own subfolders are not searched."""
    found: dict[str, Path] = {}
    visited = 0
    level = [root]
    for _ in range(depth + 1):
        below: list[Path] = []
        for folder in level:
            visited += 1
            if visited > SCAN_MAX_DIRS:
                return found
            if any((folder / marker).exists() for marker in _IGNORE_MARKERS):
                continue
            name = package_xml_name(folder) if _is_file(folder / "package.xml") else None
            if name is not None:
                found.setdefault(name, folder)
                continue
            try:
                entries = sorted(os.scandir(folder), key=lambda e: e.name)
            except OSError:
                continue
            below.extend(Path(e.path) for e in entries if not e.name.startswith(".") and _entry_is_dir(e))
        level = below
    return found


def _entry_is_dir(entry: os.DirEntry[str]) -> bool:
    try:
        return entry.is_dir()
    except OSError:
        return False


def _ament_share(prefix: Path, name: str) -> Path | None:
    if not _PACKAGE_NAME.match(name):
        return None
    marker = prefix / "share" / "ament_index" / "resource_index" / "packages" / name
    share = prefix / "share" / name
    return share if _is_file(marker) and _is_dir(share) else None


def _split(value: str) -> list[Path]:
    return [Path(part) for part in value.split(os.pathsep) if part.strip()]


class PackageIndex:
    """Where ROS packages are, for ``$(find pkg)`` and ``package://pkg/...``; see the module docstring."""

    def __init__(
        self,
        *,
        pins: Mapping[str, Path] | None = None,
        paths: Sequence[Path] = (),
        description: Path | None = None,
        ros_package_path: Sequence[Path] = (),
        ament_prefix_path: Sequence[Path] = (),
    ) -> None:
        self.pins = {name: Path(folder) for name, folder in (pins or {}).items()}
        self.paths = tuple(Path(p) for p in paths)
        self.description = description
        self.ros_package_path = tuple(Path(p) for p in ros_package_path)
        self.ament_prefix_path = tuple(Path(p) for p in ament_prefix_path)
        self._scans: dict[Path, dict[str, Path]] = {}
        self._above: dict[Path, tuple[list[Path], list[Path], list[Path]]] = {}
        self._found: dict[tuple[str, Path | None], Path | None] = {}

    @classmethod
    def from_environ(cls, environ: Mapping[str, str] | None = None, *, description: Path | None = None) -> PackageIndex:
        env = os.environ if environ is None else environ
        return cls(
            description=description,
            ros_package_path=_split(env.get("ROS_PACKAGE_PATH", "")),
            ament_prefix_path=_split(env.get("AMENT_PREFIX_PATH", "")),
        )

    @classmethod
    def from_args(
        cls, package_paths: Sequence[str], *, description: Path | None, environ: Mapping[str, str]
    ) -> PackageIndex:
        """From the CLI's repeatable ``--package-path DIR|NAME=DIR`` values and the environment.
        Raises :class:`UsageError` for a path that is not a folder."""
        pins: dict[str, Path] = {}
        paths: list[Path] = []
        for value in package_paths:
            name, sep, folder = value.partition("=")
            pinned = bool(sep) and _PACKAGE_NAME.match(name) is not None and "/" not in name
            target = Path(folder if pinned else value).expanduser()
            if not _is_dir(target):
                raise UsageError(f"--package-path {value!r}: {str(target)!r} is not a folder")
            if pinned:
                pins[name] = target
            else:
                paths.append(target)
        index = cls.from_environ(environ, description=description)
        index.pins, index.paths = pins, tuple(paths)
        return index

    # ------------------------------------------------------------------ lookup

    def find(self, name: str, *, near: Path | None = None) -> Path:
        """The folder of package ``name``; ``near`` (a folder, e.g. the including file's) is walked up
        besides the description's. Raises :class:`PackageError` saying where it looked."""
        found = self.lookup(name, near=near)
        if found is None:
            raise PackageError(f"package {name!r} not found; looked in {self.where(near=near)}")
        return found

    def lookup(self, name: str, *, near: Path | None = None) -> Path | None:
        """:meth:`find`, returning None when the package is nowhere (answers are remembered)."""
        key = (name, None if near is None else Path(near))
        if key not in self._found:
            self._found[key] = self._lookup(name, near)
        return self._found[key]

    def _lookup(self, name: str, near: Path | None) -> Path | None:
        if name in self.pins:
            return self.pins[name]
        for start in self._starts(near):
            packages, siblings, prefixes = self._around(start)
            for folder in packages:
                if package_xml_name(folder) == name:
                    return folder
            for folder in siblings:
                hit = self._scan(folder).get(name)
                if hit is not None:
                    return hit
            for prefix in prefixes:
                hit = _ament_share(prefix, name)
                if hit is not None:
                    return hit
        for root in (*self.paths, *self.ros_package_path):
            hit = self._scan(root).get(name) or _ament_share(root, name)
            if hit is not None:
                return hit
        for prefix in self.ament_prefix_path:
            hit = _ament_share(prefix, name)
            if hit is not None:
                return hit
        for start in self._starts(near):  # the old rule: a folder above named like the package
            for ancestor in (start, *list(start.parents)[:WALK_UP_MAX]):
                if ancestor.name == name:
                    return ancestor
        return None

    def where(self, *, near: Path | None = None) -> str:
        """Where :meth:`find` looks, for messages (one line)."""
        places = [f"the folders above {listed(repr(str(s)) for s in self._starts(near)) or 'nothing'}"]
        places.append("--package-path " + (listed(repr(str(p)) for p in self.paths) if self.paths else "(none)"))
        for var, entries in (
            ("ROS_PACKAGE_PATH", self.ros_package_path),
            ("AMENT_PREFIX_PATH", self.ament_prefix_path),
        ):
            if len(entries) > SHOWN + 1:  # a big workspace's AMENT_PREFIX_PATH: hundreds of prefixes
                places.append(f"{var} ({len(entries)} entries: {listed(entries)})")
            else:
                places.append(f"{var} " + (":".join(str(p) for p in entries) if entries else "(unset)"))
        return "; ".join(places)

    def _starts(self, near: Path | None) -> list[Path]:
        starts = [] if near is None else [Path(near)]
        if self.description is not None:
            starts.append(Path(self.description).parent)
        unique: list[Path] = []
        for start in starts:
            absolute = Path(os.path.abspath(start))
            if absolute not in unique:
                unique.append(absolute)
        return unique

    def _around(self, start: Path) -> tuple[list[Path], list[Path], list[Path]]:
        """Packages enclosing ``start``, the folders holding their siblings, and enclosing install prefixes."""
        if start not in self._above:
            packages: list[Path] = []
            prefixes: list[Path] = []
            for ancestor in (start, *list(start.parents)[:WALK_UP_MAX]):
                if _is_file(ancestor / "package.xml"):
                    packages.append(ancestor)
                if _is_dir(ancestor / "share" / "ament_index"):
                    prefixes.append(ancestor)
            siblings: list[Path] = []
            if packages:  # the repository or workspace around the innermost package
                outer = packages[0].parent
                siblings = [outer, outer.parent] if outer.parent != outer else [outer]
            self._above[start] = (packages, siblings, prefixes)
        return self._above[start]

    def _scan(self, root: Path) -> dict[str, Path]:
        if root not in self._scans:
            self._scans[root] = scan_packages(root) if _is_dir(root) else {}
        return self._scans[root]

    # ------------------------------------------------------------------ URIs

    def resolve_uri(self, uri: str, *, base_dir: Path) -> Path | None:
        """The local file for a URDF ``filename``: ``package://pkg/rel``, ``package:///pkg/rel`` or
        ``package:///abs`` (empty package part, accepted like urdfdom), ``file://``, a plain path
        (relative ones against ``base_dir``); None if it is not an existing file."""
        return self.explain(uri, base_dir=base_dir)[0]

    def explain(self, uri: str, *, base_dir: Path) -> tuple[Path | None, str]:
        """:meth:`resolve_uri` with the reason when nothing is found (for a warning)."""
        parts = urlsplit(uri)
        scheme = parts.scheme.lower() if len(parts.scheme) > 1 else ""  # "C:" is a drive, not a scheme
        if scheme == "package":
            return self._package_uri(uri, unquote(parts.netloc), unquote(parts.path), base_dir)
        if scheme == "file":
            local = Path(unquote(parts.netloc + parts.path))
        elif scheme:
            return None, f"mesh {_quote(uri)} has unsupported URI scheme {scheme!r}"
        else:
            local = Path(uri)
        candidate = local if local.is_absolute() else base_dir / local
        if _is_file(candidate):
            return candidate, ""
        return None, f"mesh file {_quote(uri)} not found"

    def _package_uri(self, uri: str, package: str, path: str, base_dir: Path) -> tuple[Path | None, str]:
        rest = path.lstrip("/")
        if not package:  # package:///pkg/rel (read as package://pkg/rel), else package:///abs/path
            package, _, rest = rest.partition("/")
            if self.lookup(package, near=base_dir) is None:
                absolute = Path("/", path.lstrip("/"))
                if _is_file(absolute):
                    return absolute, ""
        folder = self.lookup(package, near=base_dir)
        if folder is None:
            return None, f"mesh {_quote(uri)}: package {package!r} not found (looked in {self.where(near=base_dir)})"
        candidate = folder / rest
        if _is_file(candidate):
            return candidate, ""
        return None, f"mesh {_quote(uri)} not found in package {package!r} ({str(folder)!r})"

    def iter_known(self) -> Iterator[tuple[str, Path]]:
        """Pinned and scanned packages found so far (for diagnostics and tests)."""
        yield from self.pins.items()
        for scan in self._scans.values():
            yield from scan.items()


def _quote(value: str, limit: int = 200) -> str:
    if len(value) > limit:
        value = value[: limit // 2] + "…" + value[-(limit // 2) :]
    return repr(value)


def uri_package(uri: str) -> str | None:
    """The package a ``package://pkg/rel`` (or ``package:///pkg/rel``) URI names; None for other URIs."""
    parts = urlsplit(uri)
    if parts.scheme.lower() != "package":
        return None
    package = unquote(parts.netloc) or unquote(parts.path).lstrip("/").partition("/")[0]
    return package or None


def expected_path(packages: PackageIndex, uri: str, *, base_dir: Path) -> Path | None:
    """Where :meth:`PackageIndex.resolve_uri` would find ``uri``'s file, whether or not it is there (``--watch``
    watches a missing mesh); None when no place can be named (a package not found, another scheme)."""
    parts = urlsplit(uri)
    scheme = parts.scheme.lower() if len(parts.scheme) > 1 else ""
    if scheme == "package":
        package, rest = unquote(parts.netloc), unquote(parts.path).lstrip("/")
        if not package:
            package, _, rest = rest.partition("/")
        folder = packages.lookup(package, near=base_dir)
        return folder / rest if folder is not None else None
    if scheme and scheme != "file":
        return None
    local = Path(unquote(parts.netloc + parts.path)) if scheme else Path(uri)
    return local if local.is_absolute() else base_dir / local


def missing_files(packages: PackageIndex, uris: Iterable[str], *, base_dir: Path) -> tuple[Path, ...]:
    """Where the files of ``uris`` that are not there would be (:func:`expected_path`), each once."""
    wanted = (expected_path(packages, uri, base_dir=base_dir) for uri in uris)
    return tuple(dict.fromkeys(p for p in wanted if p is not None and not _is_file(p)))
