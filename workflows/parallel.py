"""The fits of one comparison run side by side, in worker processes.

Why: much of a fit's wall time is XLA compilation (jaxns' nested-sampling program alone
compiles for 10-17 s per model on the 2-core machine), and a compilation runs on one
thread, while the sampling phases use about two cores. On a machine with more cores,
fits side by side use the cores one fit leaves idle; on 2 cores they gain nothing
(:func:`resolve_workers`).

Why processes and not threads: NumPyro's effect handlers live on one module-global stack,
so two models traced by two threads of one process would corrupt each other's traces.

Same seed, same numbers: a worker builds the same model from the same data, compiles the
same programs and draws from the same keys as the in-process path (``workers = 1``), so
draws and evidence agree to round-off (bit for bit on this machine; within 1e-8 relative
in CI, where another process's XLA threads may split reductions differently; checked in
tests/test_cli.py).
"""

from __future__ import annotations

import json
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["Job", "run_jobs", "resolve_workers"]

# data and model inputs of the worker process, built once per (data, likelihood options)
_DATA: dict[str, tuple[Any, dict[str, Any]]] = {}


@dataclass(frozen=True)
class Job:
    """One unit of work: ``kind`` "fit" (pipeline.fit_law: NUTS, gate, LOO, evidence,
    files under ``out``), "eta" (the eta draws of one extra viscoelastic NUTS fit,
    compare_outputs.nuts_eta, with ModelSpec keywords ``spec`` and ``seed_offset``) or
    "ns" (nested-sampling evidence of ``spec`` with cfg's live points and seed)."""

    key: str
    kind: str
    name: str
    spec: Any
    cfg: dict[str, Any] = field(hash=False)
    out: str = ""
    seed_offset: int = 0


def resolve_workers(value: int | None, n_jobs: int) -> int:
    """Worker processes for ``n_jobs`` jobs: 0 (or None) = one per two usable cores (at
    most 4), else the integer given; 1 runs everything in this process.

    One per two cores because one fit alone already keeps about two cores busy (NUTS
    chains and jaxns shards on the host devices): on the 2-core machine the full cold
    comparison took 388 s with two workers against 404 s with one (a two-law run 114 s
    against 136 s), not worth twice the memory."""
    if not value:
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
            else (os.cpu_count() or 1)
        value = min(4, cores // 2)
    return max(1, min(int(value), n_jobs))


def _data(cfg: dict[str, Any]):
    from inference.likelihood import model_inputs

    from .pipeline import load_data

    key = json.dumps({"data": cfg["data"], "likelihood": cfg["likelihood"]}, sort_keys=True,
                     default=str)
    if key not in _DATA:
        ds = load_data(cfg)
        _DATA[key] = (ds, model_inputs(ds))
    return _DATA[key]


def _run(job: Job, resume: bool, ds: Any = None, inputs: dict | None = None) -> Any:
    from . import compare_outputs
    from .pipeline import fit_law

    if ds is None:
        ds, inputs = _data(job.cfg)
    if job.kind == "fit":
        return fit_law(job.name, job.spec, inputs, ds, job.cfg, Path(job.out), resume=resume)
    if job.kind == "eta":
        return compare_outputs.nuts_eta(job.spec, inputs, job.cfg, job.seed_offset)
    if job.kind == "ns":
        from inference.evidence import nested_sampling_log_z
        from inference.numpyro_models import build_model

        return nested_sampling_log_z(build_model(job.spec), {"data": inputs},
                                     num_live_points=job.cfg["evidence"]["live_points"],
                                     seed=job.cfg["seed"])
    raise ValueError(f"unknown job kind {job.kind!r}")


def _worker(job: Job, resume: bool) -> Any:
    res = _run(job, resume)
    # a LawRun's InferenceData travels through its netCDF file, not through the pipe
    return ("fit", res.summary) if job.kind == "fit" else (job.kind, res)


def _init(n_devices: int, log_dir: str, quiet: bool) -> None:
    from .cli import _enable_x64, host_devices

    host_devices(n_devices)  # inherited from the parent's environment in practice
    _enable_x64()
    from inference.sample import configure

    configure(n_devices)
    from .cmd_compare import setup_logging

    setup_logging(Path(log_dir), quiet)


def run_jobs(jobs: list[Job], *, workers: int, ds: Any, inputs: dict[str, Any],
             resume: bool, log_dir: Path, quiet: bool, n_devices: int) -> dict[str, Any]:
    """Run ``jobs`` (in the order given, longest first is best) and return key -> result:
    a pipeline.LawRun for "fit" jobs, the eta draws for "eta" jobs, an EvidenceResult for
    "ns" jobs. ``workers`` = 1 runs
    them here, one after the other."""
    if workers <= 1:
        return {j.key: _run(j, resume, ds, inputs) for j in jobs}
    from inference.sample import load_idata

    from .pipeline import LawRun

    ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: no forked JAX state
    results: dict[str, Any] = {}
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init,
                             initargs=(n_devices, str(log_dir), quiet)) as pool:
        futures = {j.key: (j, pool.submit(_worker, j, resume)) for j in jobs}
        for key, (job, fut) in futures.items():
            kind, value = fut.result()
            if kind == "fit":
                idata = load_idata(Path(job.out) / "idata" / f"{job.name}.nc")
                results[key] = LawRun(job.name, value, idata)
            else:
                results[key] = value
    return results
