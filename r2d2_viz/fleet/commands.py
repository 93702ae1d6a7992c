"""The command-line side of the fleet (called by :mod:`r2d2_viz.cli`): ``--bag … --save-dir DIR`` with one
overall progress bar on a terminal (bags and bytes done, ETA; off a terminal only the summary), and
``--dataset DIR`` served or summed up. Returns exit codes: 0 done, 2 when any bag failed, 130 interrupted.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from r2d2_viz.errors import UsageError, listed
from r2d2_viz.fleet.convert import FleetReport, Outcome, Progress, plan_jobs, run_local
from r2d2_viz.msgs.images import EncoderName, require_av

EXIT_OK, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 2, 130


def _say(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def fleet_main(args: argparse.Namespace) -> int:
    """``--save-dir`` and ``--dataset`` and their flags, checked; the exit code."""
    given = (("--jobs", args.jobs), ("--force", args.force or None), ("--ray", args.ray))
    fleet_only = [flag for flag, value in given if value is not None]
    if args.save_dir is None and args.dataset is None:
        raise UsageError(f"{(fleet_only or ['--summary'])[0]} goes with --save-dir (or --summary with --dataset)")
    if args.save_dir is not None and args.dataset is not None:
        raise UsageError("--save-dir converts bags and --dataset serves recordings: one at a time")
    if args.save_dir is not None:
        if args.video is not None:
            require_av()
        if not args.bag:
            raise UsageError("--save-dir DIR: give the bags to convert with --bag BAG [BAG ...]")
        others = [f for f, v in (("--save", args.save), ("--urdf", args.urdf), ("--motion", args.motion)) if v]
        if others or args.xacro_args:
            raise UsageError(f"--save-dir converts each bag as it is: {(others or ['xacro arguments'])[0]} not taken")
        if args.jobs is not None and args.jobs < 1:
            raise UsageError(f"--jobs must be at least 1, got {args.jobs}")
        return convert_command(
            args.bag,
            args.save_dir,
            jobs=args.jobs,
            force=args.force,
            ray=args.ray,
            use_ray=args.ray is not None,
            video=args.video,
        )
    if args.bag or fleet_only:
        raise UsageError(f"--dataset serves recordings; {'--bag' if args.bag else fleet_only[0]} goes with --save-dir")
    live = [f for f, on in (("--spawn", args.spawn), ("--serve", args.serve), ("--headless", args.headless)) if on]
    if len(live) > 1:
        raise UsageError(f"choose one of {' and '.join(live)}")
    return dataset_command(
        args.dataset,
        summary=args.summary,
        bind=args.bind,
        port=51234 if args.port is None else args.port,
        viewer=live[0].lstrip("-") if live else "spawn",
        web_port=args.web_port,
    )


def convert_command(
    bags: list[Path],
    out_dir: Path,
    *,
    jobs: int | None,
    force: bool,
    ray: str | None,
    use_ray: bool,
    video: EncoderName | None = None,
) -> int:
    start = time.perf_counter()
    report = FleetReport()
    if use_ray:
        from r2d2_viz.fleet.ray_run import import_ray

        import_ray()  # before anything: without Ray, one line saying how to install it
    work = plan_jobs(bags, out_dir, force=force, report=report, video=video)
    for path, why in report.failed:
        _say(f"error: {why}" if str(path) in why else f"error: {path}: {why}")
    for path, first in report.duplicates:
        link = " (a link to it)" if path.is_symlink() else ""
        _say(f"note: {path}: the same bag as {first}{link}; converted once")
    total = sum(job.size for job in work)
    with _progress(len(work), total) as advance:

        def on_done(outcome: Outcome) -> None:
            if outcome.error is None:
                report.converted.append(outcome)
            else:
                report.failed.append((outcome.job.bag, outcome.error))
                error = outcome.error
                _say(f"error: {error}" if str(outcome.job.bag) in error else f"error: {outcome.job.bag}: {error}")
            advance(outcome)

        if not work:
            finished = True
        elif use_ray:
            from r2d2_viz.fleet.ray_run import run_ray

            local = {"num_cpus": jobs} if jobs and not ray else None  # --jobs sizes a local Ray
            finished = run_ray(work, address=ray or None, on_done=on_done, init=local)
        else:
            finished = run_local(work, workers=jobs or os.cpu_count() or 1, on_done=on_done)
    report.interrupted = not finished
    seconds = time.perf_counter() - start
    parts = [f"{len(report.converted)} converted"]
    if report.up_to_date:
        parts.append(f"{len(report.up_to_date)} up to date")
    if report.failed:
        parts.append(f"{len(report.failed)} failed")
    if report.duplicates:
        parts.append(f"{len(report.duplicates)} given twice")
    if report.interrupted:
        ended = {o.job.bag for o in report.converted} | {path for path, _ in report.failed}
        not_done = [str(job.bag) for job in work if job.bag not in ended]
        parts.append(f"{len(not_done)} not done (interrupted)")
        if not_done:
            _say(f"not done (interrupted): {listed(not_done)}")
    _say(f"r2d2-viz: {', '.join(parts)} → {out_dir} in {seconds:.1f} s")
    if report.interrupted:
        return EXIT_INTERRUPTED
    return EXIT_BAD_INPUT if report.failed else EXIT_OK


@contextmanager
def _progress(n_bags: int, n_bytes: int) -> Iterator[Progress]:
    """One overall bar on a terminal (stderr); nothing off one."""
    if not sys.stderr.isatty() or n_bags == 0:
        yield lambda _: None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        DownloadColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    bar = Progress(
        TextColumn("[bold]converting"),
        BarColumn(),
        TextColumn("{task.fields[bags]}/{task.fields[of]} bags"),
        DownloadColumn(),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        transient=True,
    )
    with bar:
        task = bar.add_task("fleet", total=max(1, n_bytes), bags=0, of=n_bags)
        done = 0

        def advance(outcome: Outcome) -> None:
            nonlocal done
            done += 1
            bar.update(task, advance=outcome.job.size, bags=done)

        yield advance


def dataset_command(
    directory: Path,
    *,
    summary: str | None,
    bind: str,
    port: int,
    viewer: str,
    web_port: int,
) -> int:
    from r2d2_viz.fleet.dataset import fleet_summary, serve_dataset

    if summary is None:
        serve_dataset(directory, bind=bind, port=port, viewer=viewer, web_port=web_port, say=_say)
        return EXIT_OK
    table: Any = fleet_summary(directory)
    from r2d2_viz.fleet.summary import format_summary, write_summary

    if summary == "-":
        print(format_summary(table), flush=True)
    else:
        write_summary(table, Path(summary))
        _say(f"r2d2-viz: {table.num_rows} recordings summed up in {summary}")
    return EXIT_OK
