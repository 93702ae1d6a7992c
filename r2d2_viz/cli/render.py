"""The command-line side of ``--render`` (issue 45): its flags checked, one video per bag (``--save-dir``), one
summary line per video. Library errors become one line and exit 2 in :mod:`r2d2_viz.cli.command`."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from r2d2_viz.errors import R2d2VizError, UsageError, shown, stderr_line

EXIT_OK, EXIT_BAD_INPUT = 0, 2
NOT_WITH = ("save", "spawn", "serve", "connect", "headless", "ros", "dataset", "realtime", "watch", "list", "tree")
"""Flags that ask for another end of the run than a video."""
FLEET_ONLY = ("jobs", "ray", "force", "summary")
"""The fleet's flags that --render does not take: its bags are rendered one after the other."""


def _say(message: str) -> None:
    print(stderr_line(f"r2d2-viz: {message}"), file=sys.stderr, flush=True)


def render_main(args: argparse.Namespace) -> int:
    """``--render OUT`` with a bag (or a motion), or ``--bag … --save-dir DIR --render mp4|gif``; the exit code."""
    from r2d2_viz.msgs.images import require_av
    from r2d2_viz.run.video_file import parse_size, video_suffix

    flags = (*NOT_WITH, *FLEET_ONLY)
    given = [f"--{name.replace('_', '-')}" for name in flags if getattr(args, name, None) not in (None, False)]
    if args.tf_tree is not None:
        given.append("--tf-tree")
    if given:
        raise UsageError(f"--render writes a video; it does not combine with {given[0]}")
    size = parse_size(args.size)
    if args.save_dir is None:
        if args.bag is not None and len(args.bag) > 1:
            raise UsageError(f"{len(args.bag)} bags: give --save-dir DIR to render one video each")
        video_suffix(args.render)
        require_av()
        jobs = [(args.bag[0] if args.bag else None, args.render)]
    else:
        if not args.bag:
            raise UsageError("--save-dir DIR --render: give the bags to render with --bag BAG [BAG ...]")
        suffix = args.render.suffix or "." + args.render.name.lstrip(".")  # --render mp4, .gif or x.mp4
        video_suffix(Path(f"video{suffix}"))
        require_av()
        jobs = _fleet_jobs(args.bag, args.save_dir, suffix.lower())
    return _render_all(args, jobs, size)


def _fleet_jobs(bags: list[Path], out_dir: Path, suffix: str) -> list[tuple[Path | None, Path]]:
    """Each bag and its video, ``DIR/<bag name><suffix>`` (the name ``--save-dir`` gives its recording)."""
    from r2d2_viz.fleet.convert import check_out_dir
    from r2d2_viz.fleet.identity import identify

    check_out_dir(out_dir)
    jobs: list[tuple[Path | None, Path]] = []
    for bag in bags:
        out = out_dir / f"{identify(bag).name}{suffix}"
        if any(out == taken for _, taken in jobs):
            raise UsageError(f"{bag}: another bag of that name would also be {out}; rename one")
        jobs.append((bag, out))
    return jobs


def _render_all(args: argparse.Namespace, jobs: list[tuple[Path | None, Path]], size: tuple[int, int]) -> int:
    from r2d2_viz.cli.run_args import run_config
    from r2d2_viz.run.render import RenderConfig, render

    said_software: list[bool] = [False]
    failed = 0
    for bag, out in jobs:
        config = run_config(args, bag=bag)
        video = RenderConfig(out=out, size=size, fps=args.fps, view=args.view)
        try:
            result = render(config, video, say=_say, said_software=said_software)
        except R2d2VizError as exc:
            if len(jobs) == 1:
                raise
            failed += 1
            _say(f"error: {bag}: {exc}")
            continue
        _say(
            shown(
                f"{result.frames} frames ({result.seconds:.1f} s at {args.fps:g} fps, {size[0]}x{size[1]}) "
                f"of {result.view!r} to {result.out}"
            )
        )
    return EXIT_BAD_INPUT if failed else EXIT_OK
