"""Outputs of ``beadrod compare``: the data and truth blocks, the tension, the fit checks,
the figures, the tables and the report.

The tension statistics are computed in :func:`inference.evidence.tension.analyse_tension` from
the fits this module schedules (:func:`tension_jobs`, run by workflows.pipeline.parallel); this
module adds what only the workflow knows (gate status, figure draws, files). Every key of
``result.json`` and every column of ``comparison.csv`` is documented in docs/outputs.md.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import numpy as np

from beadrod.data.io import atomic_path, write_json, write_text
from beadrod.workflows.config import shift_noise

__all__ = ["data_block", "exclusions", "tension", "tension_jobs", "nuts_eta", "fit_checks",
           "law_loss_rows", "loss_shift", "observable_preference", "report_extras", "figures",
           "write_outputs"]

log = logging.getLogger("beadrod")


def exclusions(excluded: Any) -> list[dict[str, Any]]:
    """The drive sweeps a processed dataset excluded, per protocol in data order: protocol
    id, number of sweeps, their lines in measurements.csv (as an editor numbers them),
    their steps, and the reason (the 2 % rule names the reference step that tripped it).
    ``beadrod validate`` prints the same list."""
    if excluded is None or not len(excluded):
        return []
    out = []
    for pid, grp in excluded.groupby("protocol", sort=False):
        col = "line" if "line" in grp else "row" if "row" in grp else None
        out.append({"protocol": str(pid), "n": int(len(grp)),
                    "lines": sorted(int(r) for r in grp[col]) if col else [],
                    "steps": sorted({int(s) for s in grp["step"]}) if "step" in grp else [],
                    "reason": str(grp["reason"].iloc[0])})
    return out


def data_block(ds: Any) -> dict[str, Any]:
    """What the report says about the data (JSON-ready; docs/outputs.md)."""
    from beadrod.workflows.report.truth import world_truth

    truth = getattr(ds, "truth", None)
    scene = getattr(ds, "scene", None)
    young_range = getattr(scene, "young_range", None)
    opts = dict(getattr(ds, "options", {}) or {})
    return {"source": str(getattr(ds, "source", "")), "hash": ds.data_hash,
            "scene": getattr(scene, "name", None),
            "n_protocols": int(ds.n_protocols),
            "protocol_ids": [str(p) for p in getattr(ds, "protocol_ids", ())],
            "n_drive": int(len(ds.drive_shift)),
            "n_excluded": int(len(ds.excluded)) if ds.excluded is not None else 0,
            "excluded": exclusions(ds.excluded),
            "n_q_missing": int(np.count_nonzero(~np.isfinite(np.asarray(ds.q_ref, float)))),
            "warnings": [str(w) for w in getattr(ds, "warnings", ())],
            "two_percent_rule": opts.get("two_percent_rule"),
            "shift_reference": opts.get("shift_reference"),
            "young_range_Pa": list(young_range) if young_range is not None else None,
            "synthetic": truth is not None, "truth": world_truth(truth)}


def nuts_eta(spec_kw, inputs, cfg, seed_offset: int, name: str | None = None):
    """Draws of ``name`` (default: the law's ``tension_param``) from one NUTS fit of the
    tension's shared law (ModelSpec keywords ``spec_kw``, the law among them)."""
    from beadrod.inference.model.numpyro_models import ModelSpec, build_model
    from beadrod.inference.sampling.sample import run_nuts
    from beadrod.models.registry import get_law

    s = cfg["sampling"]
    spec = ModelSpec(**spec_kw)
    fit = run_nuts(build_model(spec), inputs,
                   num_warmup=s["warmup"], num_samples=s["samples"], num_chains=s["chains"],
                   seed=cfg["seed"] + seed_offset, target_accept=s["target_accept"],
                   predictive=False)
    param = name or get_law(spec.law).presentation.tension_param
    return np.asarray(fit.idata.posterior[param]).ravel()


def _prior_draws(param: str, n: int, seed: int) -> np.ndarray:
    import jax

    from beadrod.inference.model.priors import prior

    return np.asarray(prior(param, {}).sample(jax.random.PRNGKey(seed), (n,)))


def _pair(pair: tuple[str, str] | None) -> tuple[str, str]:
    """The tension's (shared, split) law names: ``pair``, else the registry's."""
    from beadrod.models.registry import tension_pair

    found = pair or tension_pair()
    if found is None:
        raise ValueError("no registered pair of laws with tension roles 'shared' and 'split'")
    return found


def _paper_cfg(cfg: dict[str, Any]) -> dict[str, Any]:
    # the paper pair's log Bayes factor: bridge sampling from the NUTS draws suffices
    # and no figure of its own (only its log Z and draws enter the tension's)
    return {**cfg, "evidence": {**cfg["evidence"], "methods": ["bridge"]},
            "report": {**cfg.get("report", {}), "figures": False}}


def tension_jobs(cfg: dict[str, Any], out: Path, rung: str, lik: str,
                 pair: tuple[str, str] | None = None) -> list:
    """The extra fits the tension needs, as workflows.pipeline.parallel jobs (keys 'tension:...'):
    the loss parameter from Q alone; under a rung where it enters the shift, from the
    shift alone; otherwise (and if cfg asks for it) the paper's Eq. 25 shared/split pair
    and its shift-alone fit. ``pair``: the (shared, split) law names
    (models.registry.tension_pair when None)."""
    from beadrod.inference.evidence.tension import ETA_IN_SHIFT
    from beadrod.inference.model.numpyro_models import ModelSpec
    from beadrod.workflows.pipeline.parallel import Job

    shared, split = _pair(pair)
    noise = shift_noise(cfg)
    # the viscosity from Q alone and from the shift alone: the amplitude ratios stay out
    jobs = [Job("tension:eta_q", "eta", "eta_q",
                {"law": shared, "rung": rung, "likelihood": lik, "use_shift": False,
                 "shift_noise": noise, "use_amplitude": False}, cfg, seed_offset=12)]
    shift_alone = {"law": shared, "likelihood": lik, "use_q": False, "shift_noise": noise,
                   "use_amplitude": False}
    if rung in ETA_IN_SHIFT:
        jobs.append(Job(f"tension:eta_shift:{rung}", "eta", "eta_shift",
                        {"rung": rung, **shift_alone}, cfg, seed_offset=11))
    elif cfg["tension"].get("paper_rung", True):
        for name in (shared, split):
            spec = ModelSpec(law=name, rung="paper_eq25", likelihood=lik, shift_noise=noise)
            jobs.append(Job(f"tension:{name}", "fit", f"{name}_paper_eq25", spec,
                            _paper_cfg(cfg), str(out / "tension")))
        jobs.append(Job("tension:eta_shift:paper_eq25", "eta", "eta_shift",
                        {"rung": "paper_eq25", **shift_alone}, cfg, seed_offset=11))
    return jobs


def tension(runs: dict[str, Any], inputs: dict[str, Any], ds: Any, cfg: dict[str, Any],
            out: Path, done: dict[str, Any] | None = None,
            runner: Any = None, pair: tuple[str, str] | None = None) -> dict[str, Any]:
    """The Q-versus-shift tension under the comparison's rung and under the paper's Eq. 25.

    The statistics are :func:`inference.evidence.tension.analyse_tension`'s (eta from the shift
    alone, from Q alone and jointly; their gap; split-vs-shared Bayes factor; the joint
    fit's predictive checks). Under a rung where eta does not enter the shift (first
    order, backbone: the correct physics) there is no shift-alone eta. The Q-alone fit
    does not depend on the rung and is shared by both blocks. ``done`` holds
    the results of :func:`tension_jobs` already run (workflows.pipeline.parallel); what is missing
    is run here by ``runner`` (workflows.pipeline.run.JOBS). ``pair``: the (shared, split)
    law names (models.registry.tension_pair when None). Returns the block of the
    comparison's rung with the paper block under 'paper' (if run).
    """
    from beadrod.workflows.pipeline.parallel import run_jobs

    pair = _pair(pair)
    lik = "student_t" if cfg["likelihood"]["robust"] else "normal"
    rung = runs[pair[0]].summary["rung"]
    done = dict(done or {})
    todo = [j for j in tension_jobs(cfg, out, rung, lik, pair) if j.key not in done]
    if todo:
        log.info("tension: %s", ", ".join(j.key.removeprefix("tension:") for j in todo))
        done.update(run_jobs(todo, runner=runner, workers=1, ds=ds, inputs=inputs,
                             resume=False, n_devices=1))
    eta_q = done["tension:eta_q"]
    block = _tension_block(runs, pair, inputs, cfg, rung, eta_q,
                           done.get(f"tension:eta_shift:{rung}"), out)
    if f"tension:{pair[0]}" in done:
        paper_runs = {k: done[f"tension:{k}"] for k in pair}
        block["paper"] = _tension_block(paper_runs, pair, inputs, cfg, "paper_eq25", eta_q,
                                        done["tension:eta_shift:paper_eq25"], out)
    return block


def _tension_block(runs, pair: tuple[str, str], inputs, cfg, rung: str, eta_q, eta_shift,
                   out: Path) -> dict[str, Any]:
    from beadrod.inference.evidence.tension import ETA_IN_SHIFT, analyse_tension
    from beadrod.models.registry import get_law
    from beadrod.workflows.report.tension import tension_sentences

    shared, split = (runs[k] for k in pair)
    param = get_law(pair[0]).presentation.tension_param

    def log_z(run):
        s = run.summary
        return (s["log_z"], s["log_z_err"]) if s.get("log_z") is not None else None

    in_shift = rung in ETA_IN_SHIFT
    block = analyse_tension(rung=rung, eta_q=eta_q, shared=shared.idata, split=split.idata,
                            eta_shift=eta_shift if in_shift else None,
                            log_z_shared=log_z(shared), log_z_split=log_z(split),
                            seed=cfg["seed"], param=param)
    block["log_bf_method"] = shared.summary.get("log_z_method")
    block["paragraph"] = tension_sentences(block)  # the report's two sentences
    block["fits_ok"] = {k: runs[k].summary["status"] == "ok" for k in pair}
    block["q_scale"] = None
    if "q_pred" in shared.idata.posterior and inputs.get("q_obs") is not None:
        # in natural units: the joint fit's linear Q against the measured reference Q
        block["q_scale"] = {
            "q_pred_median": float(np.median(np.asarray(shared.idata.posterior["q_pred"]))),
            "q_obs_median": float(np.median(np.asarray(inputs["q_obs"])))}
    eta_joint = np.asarray(shared.idata.posterior[param]).ravel()
    # the eta figure draws the shift-alone posterior; where eta does not enter the shift
    # that posterior is the prior, drawn here for the figure only (no statistic uses it)
    shift_draws = eta_shift if in_shift else _prior_draws(param, eta_joint.size,
                                                          cfg["seed"] + 11)
    with atomic_path(out / "idata" / f"tension_eta_samples_{rung}.npz") as tmp:
        np.savez(tmp, shift=shift_draws, q=eta_q, joint=eta_joint)
    return block


def law_loss_rows(run: Any, spec: Any, inputs: dict[str, Any], ds: Any
                  ) -> dict[str, Any] | None:
    """One fit's rows of the loss-against-shift table
    (:func:`inference.evidence.loss_shift.model_row`), computed where the fit ran (a worker
    process): ``exact``, its draws at its rung; ``paper``, the same draws at the paper's
    rung (:func:`inference.model.numpyro_models.paper_spec`: Eq. 25 where the law has it,
    else first order; the law-free baseline has no rung and one row). None where the
    data have no usable amplitude ratio; a row that fails carries ``error``."""
    from dataclasses import replace

    from beadrod.inference.evidence.loss_shift import model_row, small_amplitude
    from beadrod.inference.model.amplitude import loss_points
    from beadrod.inference.model.numpyro_models import law_of, paper_spec

    points = loss_points(ds)
    if points.x.size == 0:
        return None
    x_small = small_amplitude(points.x)

    def row(sp):
        try:
            return model_row(sp, run.idata, x_small, inputs)
        except Exception as exc:  # noqa: BLE001 (one row: the table says why)
            log.warning("%s: loss-against-shift row not computed (%s: %s)", run.name,
                        type(exc).__name__, exc)
            return {"error": f"{type(exc).__name__}: {exc}"}

    exact = row(spec)
    if law_of(spec) is None:
        return {"exact": exact, "paper": exact}
    try:
        paper = replace(spec, rung=paper_spec(spec.law).rung)
    except ValueError as exc:  # the law has no rung of the paper's
        return {"exact": exact, "paper": {"error": str(exc)}}
    return {"exact": exact, "paper": exact if paper.rung == spec.rung else row(paper)}


def loss_shift(runs: dict[str, Any], ds: Any, done: dict[str, Any] | None = None
               ) -> dict[str, Any] | None:
    """The loss-against-shift table of result.json (docs/outputs.md): x_s, per reading
    (``exact``: each fit at its rung; ``paper``: at the paper's rung, from the tension's
    Eq. 25 fit of a law where the comparison ran one, ``done`` holding it under
    'tension:NAME') each model's row, and the data's row
    (:func:`inference.evidence.loss_shift.data_row`). None where no row was computed."""
    from beadrod.inference.evidence.loss_shift import data_row, small_amplitude
    from beadrod.inference.model.amplitude import loss_points

    points = loss_points(ds)
    rows = {k: r.loss_shift for k, r in runs.items() if r.loss_shift}
    if points.x.size == 0 or not rows:
        return None
    x_small = small_amplitude(points.x)
    paper: dict[str, Any] = {}
    for name, r in rows.items():
        fit = (done or {}).get(f"tension:{name}")
        own = getattr(fit, "loss_shift", None)
        paper[name] = ({**own["exact"], "source": "the tension's Eq. 25 fit"}
                       if own and "error" not in own["exact"] else r["paper"])
    return {"x_small": x_small, "exact": {k: r["exact"] for k, r in rows.items()},
            "paper": paper, "data": data_row(points, x_small)}


def observable_preference(runs: dict[str, Any], ds: Any) -> dict[str, Any] | None:
    """The law each observable prefers by its elpd_loo, and all together by the evidence
    (:func:`inference.evidence.observables.preference_by_observable`, from each run's
    ``site_loos``, computed here where the fit did not): the laws that passed their gate
    contest, the law-free baseline is ranked but never preferred; where no law passed,
    every law contests and ``gate_ignored`` says so."""
    from beadrod.inference.evidence.observables import preference_by_observable, site_loos
    from beadrod.workflows.report.tables import is_baseline, is_failed, ranking

    laws = [r.summary for r in runs.values()]
    bases = [lw["name"] for lw in laws if is_baseline(lw)]
    ok = [lw["name"] for lw in laws if not is_failed(lw)]
    ignored = not any(n not in bases for n in ok)
    if ignored:
        laws = [{**lw, "status": "ok"} for lw in laws]
        ok = [lw["name"] for lw in laws]
    try:
        loos = {k: r.site_loos if r.site_loos is not None else site_loos(r.idata)
                for k, r in runs.items()}
        out = preference_by_observable(
            loos, ranking(laws), eligible=ok, baselines=bases,
            data_hashes={k: r.summary.get("data_hash", getattr(ds, "data_hash", None))
                         for k, r in runs.items()})
    except Exception as exc:  # noqa: BLE001 (the report says it is missing, and why)
        log.warning("preference by observable not computed (%s: %s)", type(exc).__name__, exc)
        return {"error": f"{type(exc).__name__}: {exc}"}
    out["gate_ignored"] = ignored
    return out


def fit_checks(runs: dict[str, Any]) -> dict[str, Any]:
    """LOO-PIT calibration of each law's shift predictive (inference.evidence.ranking), by law."""
    from beadrod.inference.evidence.ranking import loo_pit_summary

    out: dict[str, Any] = {}
    for name, run in runs.items():
        if run.summary.get("loo_pit") is not None:  # computed with the fit
            out[name] = run.summary["loo_pit"]
            continue
        try:
            out[name] = loo_pit_summary(run.idata, "shift_obs")
        except Exception as exc:  # noqa: BLE001 (a degenerate tiny run: say so, go on)
            out[name] = {"error": f"{type(exc).__name__}: {exc}"}
    return {"loo_pit": out}


def report_extras(runs: dict[str, Any], ds: Any) -> dict[str, Any]:
    """The result's ``checks`` (LOO-PIT per law) and ``truth_protocols`` (per-protocol
    truths of a synthetic world against the data and each fit; None for measured data)."""
    from beadrod.workflows.report.truth import protocol_truth

    idatas = {name: run.idata for name, run in runs.items()}
    return {"checks": fit_checks(runs),
            "truth_protocols": protocol_truth(getattr(ds, "truth", None), ds.protocol_ids,
                                              ds.f0, ds.q_ref, idatas)}


def figures(runs, inputs, ds, result, out: Path, processes: int = 1) -> list[dict[str, Any]]:
    from beadrod.workflows.figures.comparison import make_figures

    return make_figures(runs, inputs, ds, result, out, processes=processes)


def write_outputs(result: dict[str, Any], out: Path) -> None:
    from beadrod.workflows.config import to_toml
    from beadrod.workflows.report.document import comparison_table, render_report
    from beadrod.workflows.report.tables import resolved_config

    md, csv = comparison_table(result)
    write_text(out / "comparison.md", md)
    write_text(out / "comparison.csv", csv)
    write_text(out / "config.resolved.toml", to_toml(resolved_config(result)))
    write_json(out / "result.json", json.loads(json.dumps(result, default=_jsonable)))
    render_report(result, out)


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    return str(obj)
