"""The flags every run of a robot reads (the robot, the bag, time, frames, layout, topics, plots) as a
:class:`~r2d2_viz.runner.RunConfig`: one reading for a plain run, ``--render`` and the others."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from r2d2_viz.cli.parser import xacro_mappings
from r2d2_viz.errors import UsageError

if TYPE_CHECKING:
    from r2d2_viz.runner import RunConfig
    from r2d2_viz.viewer.sinks import SinkConfig


def shared_frames(text: str | None) -> tuple[str, ...] | None:
    """``--shared-frames map,world`` → its frames."""
    if text is None:
        return None
    frames = tuple(f.strip() for f in text.split(",") if f.strip())
    if not frames:
        raise UsageError(f"--shared-frames {text!r}: expected frame names separated by commas, such as map,world")
    return frames


def sink_config(args: argparse.Namespace, implied: bool, *, page: bool = False) -> SinkConfig:
    """Where a run goes: the sink flags; with none of them (``implied``) the native viewer, or, where no window
    can open, the web viewer on loopback (``sink.serve`` without ``--serve``: the caller says why)."""
    from r2d2_viz.viewer.sinks import DEFAULT_GRPC_PORT, SinkConfig, has_display  # rerun: not for --list

    fallback = implied and not has_display()
    return SinkConfig(
        spawn=args.spawn or (implied and not fallback),
        connect=args.connect,
        serve=args.serve or fallback,
        save=args.save,
        headless=args.headless,
        bind=args.bind,
        port=DEFAULT_GRPC_PORT if args.port is None else args.port,
        web_port=args.web_port,
        page=page,
    )


def run_config(args: argparse.Namespace, **fields: Any) -> RunConfig:
    """A run's configuration from the parsed flags; ``fields`` set what the caller decides (the sink, the bag…)."""
    from r2d2_viz.progress import wanted  # here: the runner imports rerun, which --list never needs
    from r2d2_viz.runner import RunConfig

    show = frozenset(k for k, on in (("mass", args.mass), ("inertia", args.inertia), ("axes", args.link_axes)) if on)
    common: dict[str, Any] = {
        "urdf": args.urdf,
        "mappings": xacro_mappings(args),
        "package_paths": tuple(args.package_path),
        "motion": args.motion,
        "rate": args.rate,
        "duration": args.duration,
        "bag": args.bag,
        "speed": args.speed,
        "time": args.time,
        "fixed_frame": args.fixed_frame,
        "shared_frames": shared_frames(args.shared_frames),
        "rviz": args.rviz,
        "start_offset": args.start_offset,
        "topics": tuple(args.topics) if args.topics is not None else None,
        "video": args.video,
        "progress": wanted(),
        "plots": tuple(tuple(p) for p in args.plot),
        "show": show,
    }
    return RunConfig(**{**common, **fields})
