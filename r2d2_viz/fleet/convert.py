"""Many bags → ``DIR/<bag name>.rrd``, one process per bag at a time (``--jobs``), each through
:func:`r2d2_viz.runner.run` as one bag is converted by hand.

Each output is written under a hidden temporary name beside it and renamed into place when complete, so an
interrupted or failed conversion leaves nothing half-written (what a killed worker left is removed at the
end). A bag that fails is reported and the others go on; a worker that dies fails its bag — after one retry
alone, since a dying worker also takes down the other conversions in flight in its pool.
"""

from __future__ import annotations

import atexit
import dataclasses
import glob
import json
import multiprocessing
import os
import signal
import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path

from r2d2_viz.errors import DEBUG_ENV, R2d2VizError, UsageError, listed, one_line, warn
from r2d2_viz.fleet.identity import BagId, identify, is_up_to_date, output_path
from r2d2_viz.msgs.images import EncoderName
from r2d2_viz.signals import sigterm_raises
from r2d2_viz.viewer.catalog import MARKER_PROPERTY, TOPICS_PROPERTY, recording_marker

TASKS_PER_WORKER = 32
"""Bags a worker converts before a fresh one takes its place (see :func:`convert_all`'s pool)."""
KILL_ENV = "R2D2_VIZ_FLEET_KILL"
STALL_S = 60.0
"""No bag finished for this long: the ones being converted are named (a bag on a hung mount never finishes)."""
STALL_ENV = "R2D2_VIZ_FLEET_STALL_S"
"""Overrides :data:`STALL_S` (the tests: a second or two)."""
"""Fault injection for the tests: a worker converting the bag of this name kills itself (SIGKILL)."""


@dataclass(frozen=True)
class Job:
    bag: Path
    out: Path
    name: str
    size: int
    recording_id: str
    marker: str
    video: EncoderName | None = None
    """``--video``: the cameras encoded as video (av1, h264)."""


@dataclass(frozen=True)
class Outcome:
    job: Job
    error: str | None = None
    """None: converted; else one line saying why not."""
    seconds: float = 0.0
    worker: int = 0
    """The process id of the worker that converted it (0: the calling process)."""


@dataclass
class FleetReport:
    converted: list[Outcome] = field(default_factory=list)
    failed: list[tuple[Path, str]] = field(default_factory=list)
    """(bag, why): bad input found before converting and conversions that failed."""
    up_to_date: list[Path] = field(default_factory=list)
    duplicates: list[tuple[Path, Path]] = field(default_factory=list)
    """(given, first): a path given after another that is the same bag (the same path twice, or a link to it)."""
    interrupted: bool = False


Progress = Callable[[Outcome], None]


def version() -> str:
    from r2d2_viz import __version__

    return __version__


def plan_jobs(
    bags: Iterable[Path], out_dir: Path, *, force: bool, report: FleetReport, video: EncoderName | None = None
) -> list[Job]:
    """The bags to convert; bad ones (missing, unreadable, two of one name) and up-to-date ones go in ``report``.
    A recording made with another ``video`` setting is not up to date (its marker's version says it)."""
    made_by = version() + (f"+video-{video}" if video else "")
    check_out_dir(out_dir)
    found: dict[str, list[BagId]] = {}
    seen: dict[Path, Path] = {}
    for path in bags:
        if (resolved := path.resolve()) in seen:  # one bag given twice (a glob and a name, a link): converted once
            report.duplicates.append((path, seen[resolved]))
            continue
        seen[resolved] = path
        try:
            bag = identify(path)
        except UsageError as exc:
            report.failed.append((path, str(exc)))
            continue
        found.setdefault(bag.name, []).append(bag)
    jobs = []
    for name, same in found.items():
        if len(same) > 1:
            listed = " and ".join(str(b.path) for b in same)
            for bag in same:
                report.failed.append((bag.path, f"{listed} would both be {name}.rrd: rename one (none converted)"))
            continue
        bag = same[0]
        out = output_path(out_dir, bag)
        if not force and out.exists() and is_up_to_date(out, bag, recording_marker(out), made_by):
            report.up_to_date.append(bag.path)
            continue
        jobs.append(Job(bag.path, out, bag.name, bag.size, bag.recording_id, bag.marker(made_by), video))
    return jobs


def check_out_dir(out_dir: Path) -> None:
    if out_dir.exists() and not out_dir.is_dir():
        raise UsageError(f"--save-dir {out_dir}: not a directory")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"--save-dir {out_dir}: cannot create it ({exc.strerror})") from None
    if not os.access(out_dir, os.W_OK | os.X_OK):
        raise UsageError(f"--save-dir {out_dir}: not writable")


def _topics(bag: Path) -> str | None:
    """The bag's topics as JSON ``{topic: [type, count]}``, from its index (the app's own reader, as the conversion
    reads it); None if it cannot say."""
    from r2d2_viz.sources.bags.bag import open_bag

    try:
        with open_bag(bag, warn=lambda _: None) as reader:
            topics = {t.name: [t.msgtype, t.count] for t in reader.topics.values()}
        return json.dumps(topics, sort_keys=True)
    except Exception:
        return None


def temp_path(out: Path) -> Path:
    return out.with_name(f".{out.name}.fleet-{os.getpid()}.partial")


def convert_one(job: Job) -> Outcome:
    """Convert one bag (in a worker process): never raises, never leaves a partial file."""
    from r2d2_viz.runner import RunConfig, run
    from r2d2_viz.viewer.sinks import SinkConfig

    if os.environ.get(KILL_ENV) == job.name:
        os.kill(os.getpid(), signal.SIGKILL)
    start = time.perf_counter()
    tmp = temp_path(job.out)
    properties = [(MARKER_PROPERTY, job.marker)]
    topics = _topics(job.bag)
    if topics is not None:
        properties.append((TOPICS_PROPERTY, topics))
    layout, tmp_layout = job.out.with_suffix(".rbl"), temp_path(job.out.with_suffix(".rbl"))
    sink = SinkConfig(save=tmp, recording_id=job.recording_id, properties=tuple(properties), layout_file=tmp_layout)
    try:
        run(RunConfig(bag=job.bag, sink=sink, video=job.video))
        if tmp_layout.exists():  # beside its recording: the dataset's layout when served (viewer/catalog.py)
            os.replace(tmp_layout, layout)
        os.replace(tmp, job.out)
    except R2d2VizError as exc:  # named after the output, not the hidden file the runner was given
        if getattr(exc, "stuck", False):  # Rerun's file sink deadlocked on a full disk: its threads would hold
            atexit.register(os._exit, 0)  # this worker's exit for ever (run before Rerun's own exit handler)
        return Outcome(job, one_line(exc).replace(str(tmp), str(job.out)), time.perf_counter() - start)
    except OSError as exc:  # a full disk, a name too long: the system's words, named after the output
        if exc.filename is None:
            return Outcome(job, f"unexpected {type(exc).__name__}: {one_line(exc)}", time.perf_counter() - start)
        where = str(exc.filename).replace(str(tmp), str(job.out))
        return Outcome(job, f"cannot write {where}: {exc.strerror or exc}", time.perf_counter() - start)
    except Exception as exc:
        return Outcome(job, f"unexpected {type(exc).__name__}: {one_line(exc)}", time.perf_counter() - start)
    finally:
        tmp.unlink(missing_ok=True)
        tmp_layout.unlink(missing_ok=True)
    return Outcome(job, None, time.perf_counter() - start)


def remove_partials(jobs: Iterable[Job]) -> None:
    """What killed workers left: the hidden temporary files of these outputs (and the runner's own, inside)."""
    for job in jobs:
        mine = f".{glob.escape(job.out.name)}.fleet-*.partial"  # a bag named run[4]: its brackets are no pattern
        layout = f".{glob.escape(job.out.with_suffix('.rbl').name)}.fleet-*.partial"
        # ours, the runner's own beside it (".<ours>.<pid>.partial"), the layout's
        for pattern in (mine, f".{mine}.*.partial", layout):
            for leftover in job.out.parent.glob(pattern):
                leftover.unlink(missing_ok=True)


def run_local(jobs: list[Job], *, workers: int, on_done: Progress) -> bool:
    """Convert ``jobs`` in ``workers`` processes; False if interrupted (finished outputs kept)."""
    saved = os.environ.get("RUST_LOG")
    if not os.environ.get(DEBUG_ENV):  # Rerun's own log lines (a full disk's raw ERROR) off in the workers too:
        os.environ["RUST_LOG"] = "off"  # its filter is read when they import rerun; our line names bag and cause
    try:
        with sigterm_raises():  # SIGTERM stops it as Ctrl-C does
            broken = _pool(jobs, workers, on_done)
            for job in broken:  # alone, once more: a dying worker takes the others in its pool down with it
                if _pool([job], 1, on_done):
                    on_done(Outcome(job, "its worker process died (killed, or out of memory)"))
    except KeyboardInterrupt:
        _stop_workers()  # the runner turns SIGTERM into a clean stop: its partial file removed
        return False
    finally:
        remove_partials(jobs)
        if saved is None:  # as it was for the caller (a test, a script calling this in-process)
            os.environ.pop("RUST_LOG", None)
        else:
            os.environ["RUST_LOG"] = saved
    return True


def _ignore_sigint() -> None:
    """A pool worker ignores Ctrl-C (a terminal sends it to every process of the run): the main process stops the
    workers itself, with SIGTERM, so that none starts another conversion. A worker whose app ended without
    stopping it (SIGKILL, a crash) gets SIGTERM: no worker lives on."""
    from r2d2_viz.robot.children import die_with_parent

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent()


def _convert_in_pool(job: Job) -> Outcome:
    """:func:`convert_one` in a pool's worker: SIGTERM stops the conversion (its partial file removed) and ends the
    worker, so the pool cannot hand it the next bag."""
    try:
        with sigterm_raises():
            return dataclasses.replace(convert_one(job), worker=os.getpid())
    except KeyboardInterrupt:
        os._exit(130)


def _pool(jobs: list[Job], workers: int, on_done: Progress) -> list[Job]:
    """Run ``jobs``; the ones whose worker died are returned. Ctrl-C: the bags not started are dropped, the
    workers stopped and awaited, the conversions that finished meanwhile reported, and KeyboardInterrupt raised."""
    broken: list[Job] = []
    context = multiprocessing.get_context("spawn")  # no fork of a process holding Rerun's threads
    # a fresh worker every 32 bags: Rerun keeps each recording stream's two threads (one ticking) for the life of
    # the process, so a worker converting a thousand bags would carry two thousand (max_tasks_per_child)
    size = max(1, min(workers, len(jobs) or 1))
    pool = ProcessPoolExecutor(
        size, mp_context=context, initializer=_ignore_sigint, max_tasks_per_child=TASKS_PER_WORKER
    )
    pending: dict[Future[Outcome], Job] = {pool.submit(_convert_in_pool, job): job for job in jobs}
    stall_s = float(os.environ.get(STALL_ENV) or STALL_S)
    try:
        while pending:
            done, _ = wait(pending, timeout=stall_s, return_when=FIRST_COMPLETED)
            if not done:  # none finished for a while: name the ones being converted (a hung mount, a FIFO)
                stalled = [str(job.bag) for future, job in pending.items() if future.running()]
                if stalled:
                    warn(f"no bag finished in {stall_s:g} s; still converting {listed(stalled)} (Ctrl-C stops)")
            for future in done:
                job = pending.pop(future)
                try:
                    on_done(future.result())
                except BrokenProcessPool:
                    broken.append(job)
    except KeyboardInterrupt:
        pool.shutdown(wait=False, cancel_futures=True)  # no new conversion starts
        _stop_workers()
        for future in pending:  # finished as the interrupt came: they count
            if future.done() and not future.cancelled() and future.exception() is None:
                on_done(future.result())
        # the pool's manager thread ended before the app's exit: CPython 3.11's exit handler wakes it through a pipe
        # that thread may be closing at that moment (a traceback, "Bad file descriptor", after the app's last line)
        pool.shutdown(wait=True)
        raise
    pool.shutdown(wait=True)
    return broken


def _stop_workers(timeout_s: float = 60.0) -> None:
    """SIGTERM to every worker (each removes its partial file and ends), then wait for them; SIGKILL to one that
    takes longer than ``timeout_s`` (what it left is removed by :func:`remove_partials`)."""
    children = multiprocessing.active_children()
    for child in children:
        child.terminate()
    deadline = time.monotonic() + timeout_s
    for child in children:
        child.join(max(0.0, deadline - time.monotonic()))
        if child.is_alive():
            child.kill()
            child.join(5)
