"""``beadrod compare`` and ``beadrod fit`` from start to end, and the jobs they run.

CSV -> validated dataset -> one ModelSpec per law (workflows.pipeline.fits) -> the fits, side
by side in worker processes (workflows.pipeline.parallel, run by :data:`JOBS`) -> the tension
analysis, the figures, the tables and the report (workflows.pipeline.outputs), under one
progress display (workflows.progress).

:func:`run_compare` can stop after the fits (``report=False``) and hand back a
:class:`Comparison`, whose report :func:`write_report` writes into any folder later: the
notebook API (workflows.api) fits into a private folder and writes the report where and
when it is asked to.

This module sits above the ones it uses: parallel (which imports only runtime), pipeline
and compare_outputs never import it, and the commands (cmd_compare, cmd_rungs) and the
benchmarks do. That keeps the workflows' imports free of cycles
(tests/test_cli_reliability.py checks it).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from beadrod.workflows.config import observables, shift_noise
from beadrod.workflows.pipeline.fits import (
    LawRun,
    beadrod_version,
    comparison_specs,
    fit_law,
    fit_steps,
    job_order,
    load_data,
    preferred_law,
)
from beadrod.workflows.pipeline.parallel import Job, resolve_workers, run_jobs
from beadrod.workflows.progress import RunProgress, begin, done

__all__ = ["JOBS", "Comparison", "run_compare", "write_report", "dataset_folder",
           "model_specs", "job_steps", "n_devices"]

log = logging.getLogger("beadrod")


def n_devices(cfg: dict[str, Any]) -> int:
    """Host devices for ``cfg``'s chains (one per chain, at most 8)."""
    return max(1, min(int(cfg["sampling"]["chains"]), 8))


def model_specs(cfg: dict[str, Any], names: list[str] | None,
                rung: str | None = None) -> dict[str, Any]:
    """ModelSpec per law of ``names`` under ``cfg``: its rung (or ``rung``), its noise
    model (likelihood.robust) and whether Q enters the likelihood (likelihood.use_q)."""
    lik = "student_t" if cfg["likelihood"]["robust"] else "normal"
    use_q, use_amplitude = observables(cfg)
    return comparison_specs(names, rung or cfg["rung"], lik, use_q=use_q,
                            use_amplitude=use_amplitude, shift_noise=shift_noise(cfg))


def job_steps(job: Job) -> int:
    """Progress steps a job reports (a fit: :func:`workflows.pipeline.fits.fit_steps`)."""
    return fit_steps(job.cfg) if job.kind == "fit" else 1


# data and model inputs of a worker process, built once per (data, likelihood options)
_DATA: dict[str, tuple[Any, dict[str, Any]]] = {}


def _figure_data(run: LawRun, spec: Any, inputs: dict[str, Any], ds: Any) -> Any:
    # what the figures compute from this fit, here where the fit ran (a worker process:
    # its compilation overlaps the other fits); None leaves it to the figures
    from beadrod.workflows.figures.damping import inv_q_panel
    from beadrod.workflows.figures.numbers import law_figure_data

    try:
        out = law_figure_data(run.name, spec, run.idata, inputs, ds)
        panel = inv_q_panel(run.name, run.name, run.idata, inputs, ds)
        if panel is not None:
            out["inv_q_panel"] = panel
        return out
    except Exception as exc:  # noqa: BLE001 (the figures retry it and say why)
        log.warning("%s: figure data not computed with the fit (%s: %s)", run.name,
                    type(exc).__name__, exc)
        return None


def dataset_folder(ds: Any, out: Path) -> str:
    """The folder the fits read the loaded Dataset ``ds`` from (the workers read the data
    from files): its own folder when that holds exactly its table and scene as they are
    now; otherwise (a simulated dataset held in memory, a table edited after loading)
    ``ds`` written into the run's folder ``out`` (``data/``) and read back, checked as
    any dataset folder is."""
    from beadrod.data.load import dataset_hash, load_dataset, write_dataset
    from beadrod.data.schema import DataError, canonical_csv
    from beadrod.workflows.runtime import UserError

    now = dataset_hash(canonical_csv(ds.table), ds.scene_dict)
    folder = Path(ds.path)
    try:
        if load_dataset(folder).data_hash == now:
            return str(folder.resolve())
    except (DataError, OSError):
        pass  # no such folder any more, or not a dataset: written below
    written = write_dataset(out / "data", ds.table, ds.scene_dict, ds.truth)
    if load_dataset(written).data_hash != now:  # rows the format reads otherwise
        raise UserError(f"the dataset given does not read back as itself from {written}: "
                        "write it with beadrod.data.write_dataset and pass that folder")
    return str(written.resolve())


class _Jobs:
    """The job runner of compare, fit and rungs (workflows.pipeline.parallel.JobRunner): "fit"
    (pipeline.fit_law), "eta" (the eta draws of one extra NUTS fit of the tension's law,
    compare_outputs.nuts_eta) and "ns" (nested-sampling evidence of a spec)."""

    def run(self, job: Job, resume: bool, ds: Any, inputs: dict[str, Any]) -> Any:
        if job.kind == "fit":
            run = fit_law(job.name, job.spec, inputs, ds, job.cfg, Path(job.out),
                          resume=resume, job=job.key)
            if job.cfg.get("report", {}).get("figures", False):
                run.figure_data = _figure_data(run, job.spec, inputs, ds)
            from beadrod.inference.evidence.observables import site_loos
            from beadrod.workflows.pipeline.outputs import law_loss_rows

            # the report's loss-against-shift rows and per-observable LOO, here where the
            # fit ran (a worker process: they overlap the other fits)
            run.loss_shift = law_loss_rows(run, job.spec, inputs, ds)
            run.site_loos = site_loos(run.idata)
            return run
        t0 = time.perf_counter()
        if job.kind == "eta":
            from beadrod.workflows.pipeline.outputs import nuts_eta

            begin(log, job.key, "%s: NUTS for the tension", job.key)
            value = nuts_eta(job.spec, inputs, job.cfg, job.seed_offset)
        elif job.kind == "ns":
            from beadrod.inference.evidence.log_z import nested_sampling_log_z
            from beadrod.inference.model.numpyro_models import build_model

            begin(log, job.key, "%s: nested sampling", job.key)
            value = nested_sampling_log_z(build_model(job.spec), {"data": inputs},
                                          num_live_points=job.cfg["evidence"]["live_points"],
                                          seed=job.cfg["seed"])
        else:
            raise ValueError(f"unknown job kind {job.kind!r}")
        done(log, job.key, "%s: done (%.0f s)", job.key, time.perf_counter() - t0,
             final=True)
        return value

    def run_in_worker(self, job: Job, resume: bool) -> Any:
        from beadrod.inference.model.likelihood import model_inputs
        from beadrod.workflows import lawfiles

        lawfiles.load(job.cfg.get("law_files") or [])  # the registry is per process

        key = repr((job.cfg["data"], sorted(job.cfg["likelihood"].items())))
        if key not in _DATA:
            ds = load_data(job.cfg)
            _DATA[key] = (ds, model_inputs(ds))
        res = self.run(job, resume, *_DATA[key])
        # a LawRun's InferenceData travels through its netCDF file, not through the pipe
        return ((res.summary, res.figure_data, res.loss_shift, res.site_loos)
                if job.kind == "fit" else res)

    def collect(self, job: Job, value: Any) -> Any:
        if job.kind != "fit":
            return value
        from beadrod.workflows.pipeline.idata_io import load_idata

        summary, fig_data, loss_rows, loos = value
        return LawRun(job.name, summary, load_idata(Path(job.out) / "idata" / f"{job.name}.nc"),
                      fig_data, loss_rows, loos)


JOBS = _Jobs()


def _write_report(result: dict[str, Any], runs: dict[str, LawRun], inputs: dict[str, Any],
                  ds: Any, out: Path, figures: bool, workers: int, timings: dict[str, Any],
                  t_start: float) -> None:
    from beadrod.workflows.pipeline import outputs

    # LOO-PIT per law and the per-protocol truth of a synthetic world (the report's)
    result.update(outputs.report_extras(runs, ds))
    t0 = time.perf_counter()
    result["figures"] = []
    if figures:
        begin(log, "figures", "figures")
        # the fits' worker count also writes the figures (workflows.figures.pool)
        result["figures"] = outputs.figures(runs, inputs, ds, result, out,
                                                    processes=workers)
        done(log, "figures", "figures done (%.0f s)", time.perf_counter() - t0)
    timings["figures_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - t_start
    result["timings"] = timings
    begin(log, "report", "tables and report")
    outputs.write_outputs(result, out)
    done(log, "report", "tables and report written")


@dataclass
class Comparison:
    """What the fits of a comparison leave: the result dict the report renders (its
    ``config`` the resolved configuration), the fitted laws, the model inputs and the
    processed dataset they were fitted to, the worker count, the timings so far, and
    ``elapsed_s``, the wall time from the start to the end of the fits and the tension.
    Enough for :func:`write_report` to write the report into any folder that holds the
    fits' files."""

    result: dict[str, Any]
    runs: dict[str, LawRun]
    inputs: dict[str, Any]
    ds: Any
    workers: int
    timings: dict[str, Any]
    elapsed_s: float


def write_report(comp: Comparison, out: Path, *, figures: bool | None = None) -> None:
    """The figures (``figures``; default: the configuration's ``report.figures``), the
    tables and the report of ``comp`` into ``out``, which holds its fits (laws/, idata/).
    The run's total time counts the fits and this, not the time between them."""
    if figures is None:
        figures = bool(comp.result["config"]["report"]["figures"])
    t_start = time.perf_counter() - comp.elapsed_s
    try:
        _write_report(comp.result, comp.runs, comp.inputs, comp.ds, out, figures,
                      comp.workers, comp.timings, t_start)
    except Exception as exc:  # noqa: BLE001 - whatever failed, the fits stay
        raise _report_failed(out, comp.runs, exc) from exc


def _report_failed(out: Path, runs: dict[str, LawRun], exc: Exception) -> Exception:
    """The error of a report that failed after the fits were written: the fits stay
    (laws/, idata/; ``--resume`` reuses them), the traceback goes to the log."""
    import traceback

    from beadrod.workflows.runtime import UserError, log_to_file

    if isinstance(exc, UserError | OSError):
        return exc
    log_to_file(logging.ERROR, "the report failed\n" + traceback.format_exc())
    return UserError(f"the fits of {', '.join(runs)} are written ({out / 'laws'}, "
                     f"{out / 'idata'}), but the report failed: {type(exc).__name__}: "
                     f"{exc} (traceback in {out / 'beadrod.log'}); fix the cause and rerun "
                     "with --resume to reuse the fits")


def run_compare(cfg: dict[str, Any], out: Path, *, resume: bool = False,
                law_names: list[str] | None = None, report: bool = True) -> Comparison:
    """Fit every law of ``cfg`` (or ``law_names``), run the tension analysis, write the
    fits into ``out`` and, with ``report``, the figures, tables and report
    (:func:`write_report`); return the :class:`Comparison` (``.result``: the result dict
    the report renders).

    The fits (and the tension's extra fits) run in ``cfg['workers']`` processes side by
    side (workflows.pipeline.parallel; 1 = in this process); the numbers do not depend on it.
    The tension needs both laws of the registry's tension pair (models.registry.tension_pair:
    the viscoelastic ones) and Q in the likelihood (likelihood.use_q)."""
    from beadrod.inference.model.likelihood import model_inputs
    from beadrod.models.registry import tension_pair
    from beadrod.workflows.pipeline import outputs

    t_start = time.perf_counter()
    ds = load_data(cfg)
    for warning in getattr(ds, "warnings", ()):  # data.process: what a fit must say
        log.warning("data: %s", warning)
    if ds.excluded is not None and len(ds.excluded):
        log.info("data: %d drive sweeps excluded by the 2 %% rule (the report and "
                 "`beadrod validate` list them)", len(ds.excluded))
    inputs = model_inputs(ds)
    names = law_names if law_names is not None else cfg["laws"]
    specs = model_specs(cfg, names)
    lik = next(iter(specs.values())).likelihood
    jobs = [Job(name, "fit", name, spec, cfg, str(out)) for name, spec in specs.items()]
    pair = tension_pair(specs)  # (shared, split) law names, if both are compared
    has_q = int(inputs["q_obs"].shape[0]) > 0
    do_tension = bool(cfg["tension"]["enabled"] and pair and observables(cfg)[0]
                      and has_q)
    if cfg["tension"]["enabled"] and pair and not do_tension:
        log.info("tension analysis skipped: it sets eta from Q against eta from the shift, "
                 "and %s", "likelihood.use_q = false leaves Q out"
                 if not observables(cfg)[0] else "no protocol of the data has a Q")
    if do_tension:
        jobs += outputs.tension_jobs(cfg, out, specs[pair[0]].rung, lik, pair)
    jobs.sort(key=job_order)
    workers = resolve_workers(cfg["workers"], len(jobs))
    figures = bool(cfg["report"]["figures"])
    total = sum(job_steps(j) for j in jobs) + int(do_tension) + (int(figures) + 1) * report
    if workers > 1:
        log.info("fitting %d models in %d worker processes", len(jobs), workers)
    with RunProgress(total, len(jobs), what="fits"):
        finished = run_jobs(jobs, runner=JOBS, workers=workers, ds=ds, inputs=inputs,
                            resume=resume, n_devices=n_devices(cfg))
        runs: dict[str, LawRun] = {name: finished[name] for name in specs}
        timings: dict[str, Any] = {f"fit_{k}_s": r.summary["timings"]["total_s"]
                                   for k, r in runs.items()}
        timings["fits_wall_s"] = time.perf_counter() - t_start
        timings["workers"] = workers
        tension = None
        if do_tension:
            t0 = time.perf_counter()
            begin(log, "tension", "tension analysis")
            tension = outputs.tension(runs, inputs, ds, cfg, out, finished, JOBS,
                                              pair)
            timings["tension_s"] = time.perf_counter() - t0
            done(log, "tension", "tension analysis done (%.0f s)", timings["tension_s"])
        laws = [r.summary for r in runs.values()]
        pref, why = preferred_law(laws)
        result = {
            "title": "beadrod: contact-law comparison",
            "beadrod_version": beadrod_version(),
            "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "data": outputs.data_block(ds),
            "laws": laws, "preferred": pref, "preferred_reason": why,
            "tension": tension,
            "loss_shift": outputs.loss_shift(runs, ds, finished),
            "observables": outputs.observable_preference(runs, ds),
            "config": cfg,
        }
        comp = Comparison(result, runs, inputs, ds, workers, timings,
                          time.perf_counter() - t_start)
        if report:
            write_report(comp, out, figures=figures)
    return comp
