"""The comparison pipeline behind ``beadrod compare`` and ``beadrod fit``.

CSV -> validated dataset -> one NumPyro model per law (``inference``) -> NUTS +
diagnostics gate + LOO + evidence (bridge; NS/SMC on request) -> tension analysis ->
figures, tables, report. Each finished law is cached in ``OUT/laws/NAME.json``
with the key (data hash, law config, beadrod version) so ``--resume`` skips it.
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

from ._io import write_json

__all__ = ["LawRun", "MODEL_SPECS", "job_order", "comparison_specs", "load_data", "fit_law",
           "run_compare"]

log = logging.getLogger("beadrod")


def beadrod_version() -> str:
    try:
        return version("beadrod")
    except PackageNotFoundError:  # running from a source tree
        return "0+unknown"


# One list of the models the comparison loop fits: law registry name -> ModelSpec kwargs.
MODEL_SPECS: dict[str, dict[str, Any]] = {
    "hertz": {"law": "hertz"},
    "powerlaw": {"law": "powerlaw"},
    "viscoelastic": {"law": "viscoelastic", "eta_mode": "shared"},
    "viscoelastic_split": {"law": "viscoelastic", "eta_mode": "split"},
    "jkr": {"law": "jkr"},
    "baseline": {"law": "baseline"},
}

LABELS = {
    "hertz": "Hertz",
    "powerlaw": "power law (rough)",
    "viscoelastic": "viscoelastic (shared eta)",
    "viscoelastic_split": "viscoelastic (eta_shift, eta_Q)",
    "jkr": "JKR adhesion",
    "baseline": "law-free baseline",
}

PARAM_UNITS = {
    "young": "Pa", "eta": "Pa s", "eta_shift": "Pa s", "eta_q": "Pa s", "n": "-",
    "gamma": "J/m^2", "delta0_scatter": "-", "sigma_shift": "-", "offset_down": "-",
    "sigma_logq": "-", "amp": "-", "power": "-", "mu_f0": "Hz", "tau_f0": "Hz",
    "mu_logq": "-", "tau_logq": "-", "delta0_ref_log": "log m",
}


def comparison_specs(names: list[str] | None, rung: str, likelihood: str) -> dict[str, Any]:
    """ModelSpec per requested name; the rung applies to every law that has it."""
    from inference.numpyro_models import ModelSpec

    names = list(MODEL_SPECS) if names is None else names
    unknown = [n for n in names if n not in MODEL_SPECS]
    if unknown:
        raise ValueError(f"unknown law(s) {unknown}; choose from {list(MODEL_SPECS)}")
    specs = {}
    for name in names:
        kw = dict(MODEL_SPECS[name])
        law_rung = rung
        if rung == "backbone" and kw["law"] == "jkr":
            law_rung = "first_order"  # the backbone rung covers F ~ delta^n only
        if rung == "paper_eq25" and kw["law"] != "viscoelastic":
            law_rung = "first_order"  # the paper's own formulas for the other laws
        specs[name] = ModelSpec(rung=law_rung, likelihood=likelihood, **kw)
    return specs


def load_data(cfg: dict[str, Any]):
    """ProcessedDataset from ``cfg['data']`` (None: the embedded paper_like world)."""
    import data as bd

    opts = {"two_percent_rule": cfg["likelihood"]["two_percent_rule"],
            "shift_reference": cfg["likelihood"]["shift_reference"]}
    if cfg["data"] is None:
        return bd.load_default(**opts)
    return bd.process(bd.load_dataset(cfg["data"]), **opts)


@dataclass
class LawRun:
    """What the pipeline keeps of one fitted law (JSON-ready summary + its InferenceData)."""

    name: str
    summary: dict[str, Any]
    idata: Any


def _cache_key(name: str, spec: Any, cfg: dict[str, Any], data_hash: str) -> str:
    blob = json.dumps({"law": name, "spec": spec.name, "sampling": cfg["sampling"],
                       "evidence": cfg["evidence"], "seed": cfg["seed"],
                       "data": data_hash, "version": beadrod_version()}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def _param_summary(idata: Any, truth: dict[str, Any] | None) -> list[dict[str, Any]]:
    post = idata.posterior
    rows = []
    for name in post.data_vars:
        arr = np.asarray(post[name])
        if arr.ndim != 2 or name not in PARAM_UNITS:
            continue  # per-protocol vectors and deterministics are in the idata file
        flat = arr.ravel()
        q05, q95 = np.percentile(flat, [5, 95])
        tv = (truth or {}).get(name)
        rows.append({"name": name, "unit": PARAM_UNITS[name], "mean": float(flat.mean()),
                     "sd": float(flat.std()), "q05": float(q05), "q95": float(q95),
                     "truth": float(tv) if isinstance(tv, (int, float)) else None})
    return rows


def fit_law(name: str, spec: Any, inputs: dict[str, Any], ds: Any, cfg: dict[str, Any],
            out: Path, *, resume: bool = False) -> LawRun:
    """NUTS + gate + LOO + evidence for one law; writes idata/NAME.nc and laws/NAME.json."""
    from inference import diagnostics
    from inference.bridge import bridge_sampling_log_z
    from inference.evidence import combined_agreement, nested_sampling_log_z, smc_log_z
    from inference.numpyro_models import build_model
    from inference.sample import load_idata, run_nuts, save_idata

    key = _cache_key(name, spec, cfg, ds.data_hash)
    summary_path = out / "laws" / f"{name}.json"
    idata_path = out / "idata" / f"{name}.nc"
    if resume and summary_path.exists() and idata_path.exists():
        cached = json.loads(summary_path.read_text())
        if cached.get("cache_key") == key:
            log.info("%s: reusing the finished fit (inputs unchanged)", name)
            return LawRun(name, cached, load_idata(idata_path))
        log.info("%s: inputs changed since the cached fit; refitting", name)

    s = cfg["sampling"]
    model = build_model(spec)
    log.info("%s: NUTS (%d chains x %d warmup + %d draws), model %s", name, s["chains"],
             s["warmup"], s["samples"], spec.name)
    t0 = time.perf_counter()
    fit = run_nuts(model, inputs, num_warmup=s["warmup"], num_samples=s["samples"],
                   num_chains=s["chains"], seed=cfg["seed"], target_accept=s["target_accept"],
                   data_hash=ds.data_hash, extra_attrs={"law": name})
    timings = dict(fit.timings)
    ess_min = min(400.0, 0.4 * s["samples"] * s["chains"])
    verdict = diagnostics.check(fit.idata, ess_min=ess_min)
    loo = diagnostics.loo_report(fit.idata)
    ev_cfg = cfg["evidence"]
    estimates = {}
    for method in ev_cfg["methods"]:  # in the order given: the first is the one that ranks
        if method == "ns":
            log.info("%s: evidence by nested sampling (%d live points)", name,
                     ev_cfg["live_points"])
            estimates["ns"] = nested_sampling_log_z(model, {"data": inputs},
                                                    num_live_points=ev_cfg["live_points"],
                                                    seed=cfg["seed"])
        elif method == "bridge":
            log.info("%s: evidence by bridge sampling from the NUTS draws", name)
            estimates["bridge"] = bridge_sampling_log_z(model, {"data": inputs},
                                                        fit.idata.posterior, seed=cfg["seed"])
        elif method == "smc":
            log.info("%s: evidence by tempered SMC (%d particles x %d seeds)", name,
                     ev_cfg["smc_particles"], ev_cfg["smc_seeds"])
            seeds = tuple(range(cfg["seed"], cfg["seed"] + ev_cfg["smc_seeds"]))
            estimates["smc"] = smc_log_z(model, {"data": inputs},
                                         num_particles=ev_cfg["smc_particles"], seeds=seeds)
    for k, est in estimates.items():
        timings[f"evidence_{k}_s"] = est.wall_s
    timings["total_s"] = time.perf_counter() - t0
    ests = list(estimates.values())
    agree = None
    if len(ests) >= 2:
        agree = all(combined_agreement(ests[0], e)[0] for e in ests[1:])
        if not agree:
            log.warning("%s: the two evidence estimators DISAGREE beyond their errors", name)
    failures = list(verdict.failures)
    summary = {
        "name": name, "label": LABELS.get(name, name), "model": spec.name, "rung": spec.rung,
        "status": "ok" if verdict.passed else "failed", "failures": failures,
        "diagnostics": {"rhat_max": verdict.rhat_max, "ess_bulk_min": verdict.ess_bulk_min,
                        "ess_tail_min": verdict.ess_tail_min,
                        "divergences": verdict.divergences, "ebfmi_min": verdict.bfmi_min},
        "params": _param_summary(fit.idata, getattr(ds, "truth", None)),
        "log_z": ests[0].log_z if ests else None, "log_z_err": ests[0].log_z_err if ests else None,
        "log_z_method": ests[0].method if ests else None,
        "log_z2": ests[1].log_z if len(ests) > 1 else None,
        "log_z2_err": ests[1].log_z_err if len(ests) > 1 else None,
        "log_z2_method": ests[1].method if len(ests) > 1 else None,
        "evidence_agree": agree, "evidence": {k: e.to_dict() for k, e in estimates.items()},
        "elpd_loo": loo["elpd_loo"], "elpd_loo_se": loo["se"],
        "pareto_k_bad": loo["k_bad"] + loo["k_very_bad"], "loo": loo,
        "timings": timings, "data_hash": ds.data_hash, "cache_key": key,
    }
    save_idata(fit.idata, idata_path)
    write_json(summary_path, summary)
    return LawRun(name, summary, fit.idata)


def preferred_law(laws: list[dict[str, Any]]) -> tuple[str, str]:
    """Highest evidence among laws that passed their diagnostics (baseline excluded)."""
    ok = [r for r in laws if r["status"] == "ok" and r.get("log_z") is not None
          and r["name"] != "baseline"]
    if not ok:
        return "none", "no law passed its sampling diagnostics"
    best = max(ok, key=lambda r: r["log_z"])
    others = sorted((r for r in ok if r is not best), key=lambda r: -r["log_z"])
    reason = f"highest log evidence ({best['log_z']:.1f} +- {best['log_z_err']:.1f})"
    if others:
        d = best["log_z"] - others[0]["log_z"]
        reason += f", {d:.1f} nats above {others[0]['label']}"
    base = next((r for r in laws if r["name"] == "baseline" and r.get("log_z") is not None), None)
    if base is not None and base["log_z"] > best["log_z"]:
        reason += (f"; but the law-free baseline beats it by {base['log_z'] - best['log_z']:.1f}"
                   " nats: no contact law captures the shape of the data")
    return best["name"], reason


# longest first, so that the last job to finish is a short one (measured on the embedded
# data: JKR and the baseline cost the most, the viscoelastic pair the least)
_JOB_ORDER = ("jkr", "baseline", "powerlaw", "hertz", "tension:viscoelastic",
               "tension:viscoelastic_split", "viscoelastic", "viscoelastic_split")


def job_order(job: Any) -> int:
    """Sort key of a workflows.parallel.Job: the costliest first, unknown keys last."""
    return _JOB_ORDER.index(job.key) if job.key in _JOB_ORDER else len(_JOB_ORDER)


def run_compare(cfg: dict[str, Any], out: Path, *, resume: bool = False,
                law_names: list[str] | None = None) -> dict[str, Any]:
    """Fit every law of ``cfg`` (or ``law_names``), run the tension analysis, write all
    outputs into ``out`` and return the result dict the report renders.

    The fits (and the tension's extra fits) run in ``cfg['workers']`` processes side by
    side (workflows.parallel; 1 = in this process); the numbers do not depend on it."""
    from inference.likelihood import model_inputs

    from . import compare_outputs
    from .parallel import Job, resolve_workers, run_jobs

    t_start = time.perf_counter()
    ds = load_data(cfg)
    inputs = model_inputs(ds)
    names = law_names if law_names is not None else cfg["laws"]
    lik = "student_t" if cfg["likelihood"]["robust"] else "normal"
    specs = comparison_specs(names, cfg["rung"], lik)
    jobs = [Job(name, "fit", name, spec, cfg, str(out)) for name, spec in specs.items()]
    do_tension = cfg["tension"]["enabled"] and {"viscoelastic", "viscoelastic_split"} <= set(specs)
    if do_tension:
        jobs += compare_outputs.tension_jobs(cfg, out, specs["viscoelastic"].rung, lik)
    jobs.sort(key=job_order)
    workers = resolve_workers(cfg["workers"], len(jobs))
    n_dev = max(1, min(int(cfg["sampling"]["chains"]), 8))
    if workers > 1:
        log.info("fitting %d models in %d worker processes", len(jobs), workers)
    done = run_jobs(jobs, workers=workers, ds=ds, inputs=inputs, resume=resume, log_dir=out,
                    quiet=bool(cfg.get("quiet")), n_devices=n_dev)
    runs: dict[str, LawRun] = {name: done[name] for name in specs}
    timings = {f"fit_{k}_s": r.summary["timings"]["total_s"] for k, r in runs.items()}
    timings["fits_wall_s"] = time.perf_counter() - t_start
    timings["workers"] = workers
    tension = None
    if do_tension:
        t0 = time.perf_counter()
        tension = compare_outputs.tension(runs, inputs, ds, cfg, out, done)
        timings["tension_s"] = time.perf_counter() - t0
    laws = [r.summary for r in runs.values()]
    pref, why = preferred_law(laws)
    result = {
        "title": "beadrod: contact-law comparison",
        "beadrod_version": beadrod_version(),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "data": compare_outputs.data_block(ds),
        "laws": laws, "preferred": pref, "preferred_reason": why,
        "tension": tension, "config": cfg,
    }
    t0 = time.perf_counter()
    result["figures"] = compare_outputs.figures(runs, inputs, ds, result, out) \
        if cfg["report"]["figures"] else []
    timings["figures_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - t_start
    result["timings"] = timings
    compare_outputs.write_outputs(result, out)
    return result
