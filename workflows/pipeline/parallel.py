"""The fits of one comparison run side by side, in worker processes.

Why: much of a fit's wall time is XLA compilation, which runs on one thread, while the
sampling phases use about two cores. On a machine with more cores,
fits side by side use the cores one fit leaves idle; on 2 cores they gain nothing
(:func:`resolve_workers`).

Why processes and not threads: NumPyro's effect handlers live on one module-global stack,
so two models traced by two threads of one process would corrupt each other's traces.

What a job does is not known here: :func:`run_jobs` is handed a :class:`JobRunner` (a
module-level object, so that it pickles by reference into the workers) and calls it. The
workers are set up by workflows.runtime, as the command line is, and send their log
records to this process through a queue.

Same seed, same numbers: a worker builds the same model from the same data, compiles the
same programs and draws from the same keys as the in-process path (``workers = 1``), so
draws and evidence agree to round-off (bit for bit on one machine; within 1e-8 relative
in CI, where another process's XLA threads may split reductions differently; checked in
tests/test_cli.py).
"""

from __future__ import annotations

import logging
import logging.handlers
import multiprocessing
import os
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from typing import Any, Protocol

from beadrod.workflows import runtime

__all__ = ["Job", "JobRunner", "run_jobs", "resolve_workers"]


@dataclass(frozen=True)
class Job:
    """One unit of work, as its runner reads it: ``kind`` (e.g. "fit", "eta", "ns"),
    the law ``name``, its ``spec`` (a ModelSpec or ModelSpec keywords), the resolved
    ``cfg``, the output folder ``out`` and a seed offset."""

    key: str
    kind: str
    name: str
    spec: Any
    cfg: dict[str, Any] = field(hash=False)
    out: str = ""
    seed_offset: int = 0


class JobRunner(Protocol):
    """What runs a :class:`Job`, in this process or in a worker."""

    def run(self, job: Job, resume: bool, ds: Any, inputs: dict[str, Any]) -> Any:
        """The job's result, from the data and model inputs of this process."""

    def run_in_worker(self, job: Job, resume: bool) -> Any:
        """In a worker: load the data, run, return what crosses the pipe (picklable)."""

    def collect(self, job: Job, value: Any) -> Any:
        """In this process: the result from what :meth:`run_in_worker` returned."""


def resolve_workers(value: int | None, n_jobs: int) -> int:
    """Worker processes for ``n_jobs`` jobs: 0 (or None) = two, or one per two usable
    cores where there are more (at most 4), else the integer given; 1 runs everything in
    this process.

    Two on a 2-core machine: one fit keeps both cores busy only while it samples; while it
    traces and compiles (most of a fit, and single-threaded) the other worker's fit runs
    (each process holds ~3 GB). Beyond two, one per two cores, as one sampling fit keeps
    two cores busy."""
    if not value:
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
            else (os.cpu_count() or 1)
        value = 1 if cores < 2 else min(4, max(2, cores // 2))
    return max(1, min(int(value), n_jobs))


def _worker(runner: JobRunner, job: Job, resume: bool) -> Any:
    return runner.run_in_worker(job, resume)


class _Relay(logging.Handler):
    """Parent side of the workers' log queue: each record goes to this process's logger
    of the same name (its handlers print and file it)."""

    def handle(self, record: logging.LogRecord) -> bool:
        logging.getLogger(record.name).handle(record)
        return True

    def emit(self, record: logging.LogRecord) -> None:  # pragma: no cover - handle() does
        pass


def run_jobs(jobs: list[Job], *, runner: JobRunner, workers: int, ds: Any,
             inputs: dict[str, Any], resume: bool, n_devices: int) -> dict[str, Any]:
    """Run ``jobs`` with ``runner`` and return key -> result. ``workers`` = 1 runs them
    here, one after the other, in the order given; more start that many worker processes
    (``n_devices`` host devices each) and hand them the jobs in the order given (longest
    first is best)."""
    if runner is None:
        raise TypeError("run_jobs needs the runner of its jobs (e.g. workflows.pipeline.run.JOBS)")
    if workers <= 1:
        return {j.key: runner.run(j, resume, ds, inputs) for j in jobs}
    ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: no forked JAX state
    queue = ctx.Queue()
    listener = logging.handlers.QueueListener(queue, _Relay())
    listener.start()
    results: dict[str, Any] = {}
    try:
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                                 initializer=runtime.init_worker,
                                 initargs=(n_devices, queue)) as pool:
            futures = {pool.submit(_worker, runner, j, resume): j for j in jobs}
            pending = set(futures)
            try:
                while pending:
                    finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for fut in finished:
                        job = futures[fut]
                        results[job.key] = runner.collect(job, fut.result())
            except BaseException:
                # one job failed (or Ctrl-C): the jobs not started yet are not started
                pool.shutdown(wait=True, cancel_futures=True)
                raise
    finally:
        listener.stop()
        queue.close()
    return {j.key: results[j.key] for j in jobs}
