"""``r2d2-viz --bag BAG... --export-lerobot DIR``: bags → episodes of one LeRobot v3.0 dataset.

Each bag is read in a worker (``--jobs`` processes, or Ray tasks with ``--ray``, as ``--save-dir`` fleets; one bag
or ``--jobs 1``: in this process) into an episode's parts in a hidden folder inside DIR; once all are done, the
episodes that fit are appended in the order the bags were given (:mod:`r2d2_viz.export.lerobot_dataset`). Bags
already in the dataset are skipped. A bag that fails (no joint states and no camera, no ``--action`` topic, features
unlike the dataset's) is one line, exit 2, and nothing of it is written; the others go in. Ctrl-C: nothing is
appended (exit 130); the hidden folder is removed however the run ends.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import shutil
import signal
import sys
import time
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from r2d2_viz.errors import R2d2VizError, UsageError, one_line, shown_in_line
from r2d2_viz.export.lerobot_dataset import DatasetState, NewEpisode, append, features_of, mismatch, open_dataset
from r2d2_viz.export.lerobot_episode import EpisodePart, EpisodeSpec, export_episode
from r2d2_viz.fleet.identity import identify

EXIT_OK, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 2, 130
DEFAULT_TASK = "replay the recorded robot"


@dataclass(frozen=True)
class ExportJob:
    spec: EpisodeSpec
    key: str
    name: str


@dataclass(frozen=True)
class ExportOutcome:
    job: ExportJob
    part: EpisodePart | None = None
    error: str | None = None


def _say(message: str) -> None:
    print(shown_in_line(message), file=sys.stderr, flush=True)


def export_one(job: ExportJob) -> ExportOutcome:
    """One bag's episode (in a worker): never raises."""
    try:
        return ExportOutcome(job, export_episode(job.spec))
    except R2d2VizError as exc:
        return ExportOutcome(job, error=one_line(exc))
    except OSError as exc:  # the dataset's disk full, a name too long…: the system's words and the file
        if exc.filename is None:
            return ExportOutcome(job, error=f"{job.spec.bag}: unexpected {type(exc).__name__}: {one_line(exc)}")
        return ExportOutcome(job, error=f"{job.spec.bag}: cannot write {exc.filename}: {exc.strerror or exc}")
    except Exception as exc:
        return ExportOutcome(job, error=f"{job.spec.bag}: unexpected {type(exc).__name__}: {one_line(exc)}")


def check_args(args: argparse.Namespace) -> None:
    """The flags that go with ``--export-lerobot`` (UsageError: one line)."""
    if not args.bag:
        raise UsageError("--export-lerobot DIR: give the bags to export with --bag BAG [BAG ...]")
    others = [f for f, v in (("--save", args.save), ("--save-dir", args.save_dir), ("--motion", args.motion)) if v]
    others += [f for f, v in (("--ros", args.ros), ("--dataset", args.dataset), ("--spawn", args.spawn)) if v]
    if others:
        raise UsageError(f"--export-lerobot writes a dataset; {others[0]} does not go with it")
    if not (math.isfinite(args.fps) and args.fps == int(args.fps) and 1 <= args.fps <= 1000):
        raise UsageError(f"--fps must be a whole number of frames per second from 1 to 1000, got {args.fps:g}")
    if args.jobs is not None and args.jobs < 1:
        raise UsageError(f"--jobs must be at least 1, got {args.jobs}")
    if args.task is not None and not args.task.strip():
        raise UsageError("--task: give the episodes' task as text")


def export_main(args: argparse.Namespace) -> int:
    """``--export-lerobot DIR`` and its flags; the exit code."""
    from r2d2_viz.msgs.images import require_av

    check_args(args)
    require_av()
    start = time.perf_counter()
    fps, root = int(args.fps), Path(args.export_lerobot)
    state, created = open_dataset(root, fps), not root.exists()
    robot_order = _urdf_order(args.urdf) if args.urdf is not None else None
    work = root / f".r2d2-viz-export-{os.getpid()}.partial"
    jobs, failed, skipped = [], 0, 0
    seen: set[str] = set()
    for n, path in enumerate(args.bag):
        try:
            bag = identify(path)
        except UsageError as exc:
            _say(f"error: {exc}")
            failed += 1
            continue
        key = bag.recording_id
        if state.has(key) or key in seen:
            skipped += 1
            continue
        seen.add(key)
        spec = EpisodeSpec(
            path,
            work / f"{n:06d}",
            fps=fps,
            action=args.action,
            header_time=args.time == "header",
            codec=args.lerobot_codec,
            robot_order=robot_order,
        )
        jobs.append(ExportJob(spec, key, bag.name))
    try:
        for job in jobs:
            job.spec.out.mkdir(parents=True, exist_ok=True)
        outcomes = _run(jobs, workers=args.jobs or os.cpu_count() or 1, ray=args.ray)
        episodes, errors = _fitting(outcomes, state, fps, args.lerobot_codec)
        for error in errors:
            _say(f"error: {error}")
        failed += len(errors)
        if episodes:
            append(state, episodes, task=args.task or DEFAULT_TASK, codec=args.lerobot_codec)
    except KeyboardInterrupt:
        _say("r2d2-viz: interrupted; nothing appended to the dataset")
        return EXIT_INTERRUPTED
    finally:
        shutil.rmtree(work, ignore_errors=True)
        if created and root.is_dir() and not any(root.iterdir()):
            root.rmdir()  # nothing went in: no empty dataset folder left behind
    frames = sum(e.part.frames for e in episodes)
    parts = [f"{len(episodes)} episode{'s' if len(episodes) != 1 else ''} ({frames} frames) exported"]
    if skipped:
        parts.append(f"{skipped} already in it")
    if failed:
        parts.append(f"{failed} failed")
    where = f" → {root}" if root.is_dir() else ""  # nothing went in and the folder was ours: no arrow to nowhere
    _say(f"r2d2-viz: {', '.join(parts)}{where} in {time.perf_counter() - start:.1f} s")
    return EXIT_BAD_INPUT if failed else EXIT_OK


def _urdf_order(path: Path) -> tuple[str, ...]:
    from r2d2_viz.export.lerobot_episode import urdf_joint_order

    try:
        return urdf_joint_order(path.read_text())[0]
    except OSError as exc:
        raise UsageError(f"--urdf {path}: cannot read it ({exc.strerror})") from None


def _fitting(
    outcomes: list[ExportOutcome], state: DatasetState, fps: int, codec: str
) -> tuple[list[NewEpisode], list[str]]:
    """The episodes that fit the dataset (or the first one's features), in the bags' order; the errors."""
    episodes, errors = [], []
    have = state.features
    for outcome in sorted(outcomes, key=lambda o: o.job.spec.out.name):
        if outcome.part is None:
            errors.append(outcome.error or f"{outcome.job.spec.bag}: failed")
            continue
        features = features_of(outcome.part, fps, codec)
        why = mismatch(have, features) if have else None
        if why is not None:
            errors.append(f"{outcome.job.spec.bag}: {why}; not added")
            continue
        have = have or features
        episodes.append(NewEpisode(outcome.job.key, outcome.job.name, outcome.part, outcome.job.spec.out))
    return episodes, errors


def _run(jobs: list[ExportJob], *, workers: int, ray: str | None) -> list[ExportOutcome]:
    if not jobs:
        return []
    with _progress(len(jobs)) as advance:
        if ray is not None:
            return _run_ray(jobs, ray, advance, num_cpus=workers if not ray else None)
        if workers == 1 or len(jobs) == 1:
            outcomes = []
            for job in jobs:
                outcomes.append(export_one(job))
                advance()
            return outcomes
        return _run_pool(jobs, workers, advance)


def _ignore_sigint() -> None:
    from r2d2_viz.robot.children import die_with_parent

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent()


def _run_pool(jobs: list[ExportJob], workers: int, advance: Callable[[], None]) -> list[ExportOutcome]:
    """In ``workers`` processes (spawned: no fork of a process holding threads); Ctrl-C stops them all."""
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(min(workers, len(jobs)), mp_context=context, initializer=_ignore_sigint)
    pending: dict[Future[ExportOutcome], ExportJob] = {pool.submit(export_one, job): job for job in jobs}
    outcomes = []
    try:
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                job = pending.pop(future)
                try:
                    outcomes.append(future.result())
                except Exception as exc:  # the worker died
                    outcomes.append(ExportOutcome(job, error=f"{job.spec.bag}: its worker died ({one_line(exc)})"))
                advance()
    except KeyboardInterrupt:
        pool.shutdown(wait=False, cancel_futures=True)
        for child in multiprocessing.active_children():
            child.terminate()
        raise
    pool.shutdown(wait=True)
    return outcomes


def _run_ray(
    jobs: list[ExportJob], address: str, advance: Callable[[], None], *, num_cpus: int | None
) -> list[ExportOutcome]:
    """As Ray tasks (``--ray``: a local Ray of ``num_cpus``; ``--ray ADDRESS``: a cluster that sees the paths)."""
    from r2d2_viz.fleet.ray_run import import_ray

    ray = import_ray()
    started = not ray.is_initialized()
    if started:
        local = {} if address else {"include_dashboard": False, "num_cpus": num_cpus}
        ray.init(address=address or "local", logging_level="ERROR", log_to_driver=False, **local)
    task = ray.remote(max_retries=0)(export_one)
    refs = {task.remote(job): job for job in jobs}
    outcomes = []
    try:
        while refs:
            done, _ = ray.wait(list(refs), num_returns=1)
            for ref in done:
                job = refs.pop(ref)
                try:
                    outcomes.append(ray.get(ref))
                except Exception as exc:
                    outcomes.append(ExportOutcome(job, error=f"{job.spec.bag}: its Ray worker failed ({exc})"))
                advance()
    except KeyboardInterrupt:
        for ref in refs:
            ray.cancel(ref, force=True)
        raise
    finally:
        if started:
            ray.shutdown()
    return outcomes


@contextmanager
def _progress(n_bags: int) -> Iterator[Callable[[], None]]:
    """One bar of bags done on a terminal (stderr); nothing off one."""
    if not sys.stderr.isatty():
        yield lambda: None
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(
        TextColumn("[bold]exporting"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} bags"),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=True,
    )
    with bar:
        task = bar.add_task("export", total=n_bags)
        yield lambda: bar.update(task, advance=1)
