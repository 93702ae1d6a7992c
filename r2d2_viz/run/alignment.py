"""Where each run of ``--compare`` starts on the shared timeline: its name (after its bag, unique), the time of its
alignment point (its start, or its first message on ``--align TOPIC``) and its ``--offset NAME=SECONDS``.

A run's time on the shared timeline is ``t − align_ns + offset``: the time since its alignment point. Pure; no
rerun import."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from r2d2_viz.errors import UsageError, shown_in_line

_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]+")


@dataclass(frozen=True)
class Alignment:
    """A run's alignment point (ns on its own clock) and its extra offset (s): a message at ``t`` goes to
    ``t − align_ns + offset_s`` on the shared timeline."""

    align_ns: int
    offset_s: float = 0.0

    def shift_ns(self) -> int:
        """What is added to the run's own times (ns)."""
        return round(self.offset_s * 1e9) - self.align_ns


def run_name(path: Path) -> str:
    """A bag's name as a run: its file or folder name without ``.mcap``/``.db3``/``.bag``/``.rrd``, every character
    that an entity path or a frame name would need escaped replaced by ``_``."""
    stem = path.name
    for suffix in (".mcap", ".db3", ".bag", ".rrd"):
        stem = stem.removesuffix(suffix)
    return _UNSAFE.sub("_", stem).strip("_.") or "run"


def run_names(paths: Sequence[Path]) -> list[str]:
    """Each path's :func:`run_name`, made unique: a second ``a`` is ``a-2`` (a third ``a-3``)."""
    names: list[str] = []
    for path in paths:
        base = run_name(path)
        name, k = base, 1
        while name in names:
            k += 1
            name = f"{base}-{k}"
        names.append(name)
    return names


def parse_offsets(items: Sequence[str], names: Sequence[str]) -> dict[str, float]:
    """``--offset NAME=SECONDS`` values → {run name: seconds}; an unknown name, a missing ``=`` or a number that
    is not finite is a :class:`UsageError`."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep:
            raise UsageError(f"--offset {shown_in_line(item)!r}: expected NAME=SECONDS, such as {names[-1]}=0.5")
        if name not in names:
            raise UsageError(
                f"--offset {shown_in_line(item)!r}: no run named {shown_in_line(name)!r} (runs: {', '.join(names)})"
            )
        try:
            seconds = float(value)
        except ValueError:
            seconds = math.nan
        if not math.isfinite(seconds):
            raise UsageError(f"--offset {shown_in_line(item)!r}: {shown_in_line(value)!r} is not a number of seconds")
        out[name] = seconds
    return out


def alignments(
    names: Sequence[str],
    starts_ns: Mapping[str, int],
    firsts_ns: Mapping[str, int | None] | None,
    offsets: Mapping[str, float],
    align: str | None,
) -> dict[str, Alignment]:
    """Each run's :class:`Alignment`: at its start (``starts_ns``), or with ``align`` at its first message on that
    topic (``firsts_ns``: None where the run has none, a :class:`UsageError` naming the run)."""
    out = {}
    for name in names:
        if align is None or firsts_ns is None:
            point = starts_ns[name]
        else:
            first = firsts_ns.get(name)
            if first is None:
                raise UsageError(f"--align {shown_in_line(align)}: run {name} has no message on that topic")
            point = first
        out[name] = Alignment(point, offsets.get(name, 0.0))
    return out
