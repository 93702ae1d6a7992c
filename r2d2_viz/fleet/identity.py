"""What a bag is to the fleet: its name, its output file, its stable recording id, and whether its output is
up to date.

The recording id is a UUID5 of the bag's name, total size in bytes and newest modification time (ns) of its
files: the same bag gives the same id on every run and on every machine that sees the same file (copies made
with ``cp -p`` or rsync ``-t`` keep it); bags of different names — in one output folder, all of them — or of
different sizes or times get different ids. (A hash of the contents would survive a ``touch`` but reads every
byte of bags of many gigabytes twice.) The catalog keys its segments by this id.

An output is up to date when it exists, is newer than every file of the bag, carries the bag's recording id
and the marker property (bag name, size, mtime, app version) of this version of r2d2-viz.
"""

from __future__ import annotations

import json
import os
import uuid
from dataclasses import dataclass
from pathlib import Path

from r2d2_viz.errors import UsageError

NAMESPACE = uuid.UUID("5d6c1e1a-25f1-4c0e-9a55-2d2f1ee7a25e")
"""The fleet's UUID5 namespace (fixed: changing it changes every recording id)."""
BAG_SUFFIXES = (".mcap", ".db3")


@dataclass(frozen=True)
class BagId:
    path: Path
    name: str
    """The output's stem: a rosbag2 directory's name, or a file's name without .mcap/.db3."""
    size: int
    mtime_ns: int

    @property
    def recording_id(self) -> str:
        return str(uuid.uuid5(NAMESPACE, f"{self.name}\0{self.size}\0{self.mtime_ns}"))

    def marker(self, version: str) -> str:
        """The ``r2d2_viz`` recording property of its output."""
        return json.dumps(
            {"bag": self.name, "size": self.size, "mtime_ns": self.mtime_ns, "version": version}, sort_keys=True
        )


def identify(path: Path) -> BagId:
    """A bag's identity; UsageError (one line naming it) when it is missing or unreadable."""
    if not path.exists():
        raise UsageError(f"{path}: no such bag")
    try:
        files = sorted(p for p in path.iterdir() if p.is_file()) if path.is_dir() else [path]
    except OSError as exc:
        raise UsageError(f"{path}: not readable ({exc.strerror})") from None
    if path.is_dir() and not any(p.suffix in BAG_SUFFIXES for p in files):
        raise UsageError(f"{path}: a folder with no .mcap or .db3 file is not a bag")
    unreadable = [p for p in files if not os.access(p, os.R_OK)]
    if unreadable or (path.is_dir() and not os.access(path, os.R_OK | os.X_OK)):
        raise UsageError(f"{(unreadable or [path])[0]}: not readable (permission denied)")
    try:
        stats = [p.stat() for p in files]
    except OSError as exc:
        raise UsageError(f"{path}: not readable ({exc.strerror})") from None
    named = Path(os.path.abspath(path))  # `--bag .` or `--bag ..`: named after the folder they stand for
    name = named.name if path.is_dir() else (named.stem if named.suffix in BAG_SUFFIXES else named.name)
    return BagId(path, name, sum(s.st_size for s in stats), max(s.st_mtime_ns for s in stats))


def output_path(out_dir: Path, bag: BagId) -> Path:
    return out_dir / f"{bag.name}.rrd"


def is_up_to_date(out: Path, bag: BagId, marker: tuple[str, str | None] | None, version: str) -> bool:
    """``marker``: the output's recording id and marker property (:func:`r2d2_viz.viewer.catalog.recording_marker`)."""
    try:
        newer = out.stat().st_mtime_ns >= bag.mtime_ns
    except OSError:
        return False
    return newer and marker == (bag.recording_id, bag.marker(version))
