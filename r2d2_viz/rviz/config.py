"""RViz configs (``.rviz``, ROS 1 and ROS 2) → a :class:`~r2d2_viz.rviz.spec.ViewSpec`: what the Rerun layout needs
to look like it. Read with a YAML safe loader (no tags, no objects; size-limited), then by
:mod:`r2d2_viz.rviz.read`. Pure: no rerun.
"""

from __future__ import annotations

import dataclasses
import json
from functools import lru_cache
from pathlib import Path
from typing import Any

from r2d2_viz.rviz.read import Reader
from r2d2_viz.rviz.spec import MAX_BYTES, RvizError, ViewSpec
from r2d2_viz.rviz.tools import config_tool_topics


def default_rviz_path() -> Path:
    """The tutorial's r2d2.rviz, shipped as package data beside the URDF."""
    from r2d2_viz.robot.model import asset_path

    return asset_path("r2d2.rviz")


@lru_cache(maxsize=1)
def tutorial_spec() -> ViewSpec:
    """The built-in layout's config: the tutorial's r2d2.rviz, read from ``assets/r2d2.rviz.json`` — the same
    YAML loaded once into JSON (a test keeps the two equal), so a run without ``--rviz`` needs no YAML parser."""
    from r2d2_viz.robot.model import asset_path

    return spec_from_data(json.loads(asset_path("r2d2.rviz.json").read_text()), source="r2d2.rviz")


def load_rviz(path: str | Path) -> ViewSpec:
    path = Path(path)
    name = path.name or str(path)
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise RvizError(f"{name}: file is too large ({size} bytes; the limit is {MAX_BYTES})")
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise RvizError(f"{name}: file not found ({path})") from None
    except IsADirectoryError:
        raise RvizError(f"{name}: is a directory, not an .rviz file") from None
    except UnicodeDecodeError as exc:
        raise RvizError(f"{name}: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise RvizError(f"{name}: cannot read: {exc.strerror}") from None
    return parse_rviz(text, source=name)


def parse_rviz(text: str, *, source: str = "config.rviz") -> ViewSpec:
    import yaml  # only when a config is read

    # libyaml's safe loader (~10x faster: 3 ms for r2d2.rviz against 29 ms), pure Python's where PyYAML lacks it
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    try:
        data = yaml.load(text, Loader=loader)  # a safe loader (no tags, no objects)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}: " if mark is not None else ""
        raise RvizError(f"{source}: {where}not YAML: {getattr(exc, 'problem', None) or exc}") from None
    return spec_from_data(data, source=source)


def spec_from_data(data: Any, *, source: str) -> ViewSpec:
    """An RViz config already loaded (a YAML safe load's mappings, lists and scalars) → its view spec."""
    if not isinstance(data, dict):
        raise RvizError(f"{source}: not an RViz config (expected a mapping with 'Visualization Manager')")
    manager = data.get("Visualization Manager")
    if not isinstance(manager, dict):
        raise RvizError(f"{source}: no 'Visualization Manager' mapping; is this an RViz config?")
    spec = Reader(source).spec(data, manager)
    return dataclasses.replace(spec, tool_topics=tuple(sorted(config_tool_topics(manager.get("Tools")).items())))


def wanted_topics(rviz: Path | None) -> set[str] | None:
    """The enabled displays' topics of an RViz config (None without one: every displayable topic)."""
    if rviz is None:
        return None
    topics = set()
    for t in load_rviz(rviz).topics:
        if t.enabled and t.topic:  # a DepthCloud reads its camera's info and its colour images too
            extra = (t.topic.rsplit("/", 1)[0] + "/camera_info", t.style.color_topic) if t.kind == "DepthCloud" else ()
            topics |= {t.topic, *(e for e in extra if e)}
    return topics
