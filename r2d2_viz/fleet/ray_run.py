"""The same conversions as Ray tasks (``--ray [ADDRESS]``): one task per bag, on a local Ray or a cluster.

Each task runs :func:`r2d2_viz.fleet.convert.convert_one` — the very function the local pool runs — so the
outputs are identical. On a cluster the bags and the output folder must be on storage every node sees (the
same paths). A task whose worker dies is not retried: its bag is reported failed, the others finish.
"""

from __future__ import annotations

from typing import Any

from r2d2_viz.errors import UsageError, one_line
from r2d2_viz.fleet.convert import Job, Outcome, Progress, convert_one, remove_partials

INSTALL = "pip install 'r2d2-viz[ray]'"


def import_ray() -> Any:
    try:
        import ray
    except ImportError:
        raise UsageError(f"--ray needs Ray, which is not installed: {INSTALL}") from None
    return ray


def run_ray(jobs: list[Job], *, address: str | None, on_done: Progress, init: dict[str, Any] | None = None) -> bool:
    """Convert ``jobs`` as Ray tasks; False if interrupted (finished outputs kept, the rest cancelled).

    ``address``: ``auto``, ``ray://HOST:PORT`` or ``HOST:PORT`` of a running cluster; None starts a local Ray
    for this run (``init``: more ``ray.init`` arguments, such as ``num_cpus``)."""
    ray = import_ray()
    started_here = not ray.is_initialized()
    if started_here:
        try:
            local = {} if address else {"include_dashboard": False}  # "local": a new Ray, never one found running
            ray.init(
                address=address or "local", logging_level="ERROR", log_to_driver=False, **{**local, **(init or {})}
            )
        except Exception as exc:
            where = f"--ray {address}" if address else "--ray"
            raise UsageError(f"{where}: cannot start or join Ray: {one_line(exc)}") from None
    task = ray.remote(max_retries=0)(convert_one)
    refs = {task.remote(job): job for job in jobs}
    try:
        while refs:
            done, _ = ray.wait(list(refs), num_returns=1)
            for ref in done:
                job = refs.pop(ref)
                try:
                    outcome = ray.get(ref)
                except Exception as exc:  # the worker died (WorkerCrashedError), or Ray lost the node
                    outcome = Outcome(job, f"its Ray worker failed: {_why(exc)}")
                on_done(outcome)
    except KeyboardInterrupt:
        for ref in refs:
            ray.cancel(ref, force=True)
        return False
    finally:
        remove_partials(jobs)
        if started_here:
            ray.shutdown()
    return True


def _why(exc: BaseException) -> str:
    text = one_line(exc)
    first = text.split(". ")[0]
    return f"{type(exc).__name__}: {first}"[:200]
