"""A cache of converted meshes on disk: ``$XDG_CACHE_HOME/r2d2-viz`` (default ``~/.cache/r2d2-viz``).

Entries are named by a key the caller derives from the source file's content (and the converter's versions), so
an edited mesh file is simply a new entry. Each entry also lists the other files the conversion read (textures,
material libraries) with their sha256, and is only used while those still match. Entries are written atomically
(a temporary file renamed into place), checked against their own sha256 when read (a corrupt or truncated entry
is ignored and rebuilt), and the whole folder is safe to delete at any time. Failing to write is not an error:
the run just converts again next time.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

MAGIC = b"r2d2-viz mesh cache 1\n"
APP_DIR = "r2d2-viz"
SUFFIX = ".glbentry"


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def default_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/r2d2-viz``, or ``~/.cache/r2d2-viz`` when it is unset or not absolute (XDG spec)."""
    base = os.environ.get("XDG_CACHE_HOME", "")
    root = Path(base) if base and Path(base).is_absolute() else Path.home() / ".cache"
    return root / APP_DIR


class DiskCache:
    """Converted meshes by content key; see the module docstring."""

    def __init__(self, directory: Path | None = None) -> None:
        self.directory = Path(directory) if directory is not None else default_cache_dir()

    def path(self, key: str) -> Path:
        if not key.isalnum():
            raise ValueError(f"cache key {key!r} is not alphanumeric")
        return self.directory / f"{key}{SUFFIX}"

    def get(self, key: str, read_dependency: Callable[[str], bytes | None]) -> bytes | None:
        """The payload stored under ``key``, or None if absent, corrupt, or a dependency changed.

        ``read_dependency(name)`` returns the current bytes of a file the conversion read (None if gone).
        """
        try:
            raw = self.path(key).read_bytes()
        except OSError:
            return None
        parsed = _parse(raw)
        if parsed is None:
            return None
        dependencies, payload = parsed
        for name, digest in dependencies.items():
            current = read_dependency(name)
            if current is None or sha256(current) != digest:
                return None
        return payload

    def put(self, key: str, payload: bytes, dependencies: dict[str, str]) -> None:
        """Store atomically; silently gives up when the folder cannot be written."""
        header = json.dumps({"dependencies": dependencies}, sort_keys=True).encode() + b"\n"
        body = header + payload
        entry = MAGIC + sha256(body).encode() + b"\n" + body
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=self.directory, prefix=".tmp-", suffix=SUFFIX)
        except OSError:
            return
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(entry)
            os.replace(tmp, self.path(key))
        except OSError:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def _parse(raw: bytes) -> tuple[dict[str, str], bytes] | None:
    """Dependencies and payload of an entry, or None unless it is whole (one copy: the payload's)."""
    if not raw.startswith(MAGIC):
        return None
    digest_end = raw.find(b"\n", len(MAGIC))
    body = digest_end + 1
    if digest_end < 0 or hashlib.sha256(memoryview(raw)[body:]).hexdigest().encode() != raw[len(MAGIC) : digest_end]:
        return None
    header_end = raw.find(b"\n", body)
    if header_end < 0:
        return None
    try:
        dependencies = json.loads(raw[body:header_end])["dependencies"]
    except (ValueError, KeyError, TypeError):
        return None
    if not isinstance(dependencies, dict):
        return None
    if not all(isinstance(k, str) and isinstance(v, str) for k, v in dependencies.items()):
        return None
    return dependencies, raw[header_end + 1 :]
