"""The comparison pipeline behind ``beadrod compare`` and ``beadrod fit``.

CSV -> validated dataset -> one NumPyro model per law (``inference``) -> NUTS +
diagnostics gate + LOO + evidence (bridge; NS/SMC on request) -> tension analysis ->
figures, tables, report. Each finished law is cached in ``OUT/laws/NAME.json``
with the key (data hash, law config, beadrod version) so ``--resume`` skips it.
"""

from __future__ import annotations

import functools
import hashlib
import json
import logging
import time
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

from beadrod.data.io import write_json
from beadrod.workflows.runtime import UserError

__all__ = ["LawRun", "job_order", "comparison_specs", "load_data", "fit_law",
           "fit_steps", "inputs_digest"]

log = logging.getLogger("beadrod")


def beadrod_version() -> str:
    try:
        return version("beadrod")
    except PackageNotFoundError:  # running from a source tree
        return "0+unknown"


# Units of the comparison's nuisance parameters; the laws' own parameters carry theirs
# (models.law.Param) and the baseline's are dimensionless but for mu_f0/tau_f0.
NUISANCE_UNITS = {
    "delta0_scatter": "-", "sigma_shift": "-", "kappa_shift": "-", "tau_shift": "-",
    "sigma_amp": "-", "tau_amp": "-", "offset_amp_down": "-", "loss_exponent": "-",
    "loss_gain": "-", "loss_power": "-",
    "offset_down": "-", "sigma_logq": "-",
    "amp": "-", "a_ref": "-", "power": "-", "mu_f0": "Hz", "tau_f0": "Hz", "mu_logq": "-",
    "tau_logq": "-",
}
BASELINE_LABEL = "law-free baseline"
# a second mode whose peak is this close [nat] to the sampled one's could hold a share of
# the evidence that bridge sampling (one mode) misses: log 2 if they were equal
MODE_GAP_WARN = 3.0


def model_names() -> list[str]:
    """The comparison's models: every registered law (built in or from a law file), then
    the law-free baseline. The law registry is the one list."""
    from beadrod.inference.model.numpyro_models import model_names as names

    return list(names())


def default_model_names() -> list[str]:
    """The models ``beadrod compare`` fits when no --laws are given: every registered law
    whose ``presentation.in_default_comparison`` is set (a law says in its description why
    not), then the baseline."""
    from beadrod.models.registry import get_law

    return [n for n in model_names()
            if n == "baseline" or get_law(n).presentation.in_default_comparison]


def model_labels() -> dict[str, str]:
    from beadrod.models.registry import laws

    return {**{law.name: law.presentation.label for law in laws()}, "baseline": BASELINE_LABEL}


def param_units() -> dict[str, str]:
    from beadrod.models.registry import laws

    units = dict(NUISANCE_UNITS)
    for law in laws():
        units.update({p.name: p.unit for p in law.params})
    return units


def __getattr__(name: str) -> Any:
    # MODEL_SPECS / LABELS / PARAM_UNITS follow the registry, laws added at run time too
    if name == "MODEL_SPECS":
        return {n: {"law": n} for n in model_names()}
    if name == "LABELS":
        return model_labels()
    if name == "PARAM_UNITS":
        return param_units()
    raise AttributeError(name)


def comparison_specs(names: list[str] | None, rung: str, likelihood: str, *,
                     use_q: bool = True, use_amplitude: bool = True,
                     shift_noise: str = "protocol") -> dict[str, Any]:
    """ModelSpec per requested name, every law at the same ``rung`` (the baseline has no
    rung). A law that cannot run at ``rung`` is refused with a clear message, never
    swapped for another rung."""
    from beadrod.inference.model.numpyro_models import BASELINE, ModelSpec
    from beadrod.models.registry import check_rung, get_law

    check_rung(rung, fit=True)
    known = model_names()
    if names is None:
        names = default_model_names()
        # a built-in law without a fast path at the rung would run the generic quadrature
        # at every likelihood call (the rough sphere's first order: over 19 minutes of NUTS
        # without finishing): refused by default, fitted when named
        slow = [n for n in names if n != BASELINE and get_law(n).too_slow_for_nuts(rung)]
        if slow:
            fast = [n for n in names if n not in slow]
            raise ValueError(
                f"law(s) {slow} have no fast path at rung '{rung}' (their generic quadrature "
                f"would run at every NUTS step: hours); fit the others with --laws "
                f"{','.join(fast)}, or name these too to wait for them")
    names = list(names)
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown law(s) {unknown}; choose from {known}")
    lacking = [n for n in names if n != BASELINE and rung not in get_law(n).physics.rungs]
    if lacking:
        have = {n: list(get_law(n).physics.rungs) for n in lacking}
        raise ValueError(f"law(s) {lacking} cannot be fitted at rung '{rung}' (their rungs: "
                         f"{have}); choose another --rung or leave them out with --laws")
    return {name: ModelSpec(law=name, rung=rung, likelihood=likelihood, use_q=use_q,
                            use_amplitude=use_amplitude, shift_noise=shift_noise)
            for name in names}


def _unreliable_bridge(estimates: dict[str, Any]) -> str:
    """Why the bridge estimate is not to be trusted ('' where it is, or absent)."""
    est = estimates.get("bridge")
    if est is None or est.settings.get("reliable", True):
        return ""
    return str(est.settings.get("reason") or "unreliable")


def observed(spec: Any, inputs: dict[str, Any]) -> list[str]:
    """What a fit's likelihood read: f0, and the shift, reference Q and amplitude ratios
    where its spec uses them and the data have them."""
    from beadrod.inference.model.amplitude import has_amplitudes

    out = ["f0"] if spec.use_f0 else []
    if spec.use_shift:
        out.append("shift")
    if spec.use_q and int(np.shape(inputs.get("q_obs", ()))[0]) > 0:
        out.append("Q")
    if spec.use_shift and spec.use_amplitude and has_amplitudes(inputs):
        out.append("amplitude")
    return out


def load_data(cfg: dict[str, Any]):
    """ProcessedDataset from ``cfg['data']`` (None: the embedded paper_like world)."""
    from beadrod import data as bd
    opts = {"two_percent_rule": cfg["likelihood"]["two_percent_rule"],
            "shift_reference": cfg["likelihood"]["shift_reference"]}
    if cfg["data"] is None:
        return bd.load_default(**opts)
    return bd.process(bd.load_dataset(cfg["data"]), **opts)


@dataclass
class LawRun:
    """What the pipeline keeps of one fitted law (JSON-ready summary + its InferenceData);
    ``figure_data``: what the figures compute from the fit, when it was computed with the
    fit (workflows.figures.numbers.law_figure_data; None: the figures compute it);
    ``loss_shift``: its rows of the loss-against-shift table and ``site_loos`` its
    PSIS-LOO per observed site, both computed with the fit
    (workflows.pipeline.outputs.law_loss_rows, inference.evidence.observables.site_loos;
    None: not computed)."""

    name: str
    summary: dict[str, Any]
    idata: Any
    figure_data: dict[str, Any] | None = None
    loss_shift: dict[str, Any] | None = None
    site_loos: dict[str, Any] | None = None


def _param_summary(idata: Any, truth: dict[str, Any] | None) -> list[dict[str, Any]]:
    post = idata.posterior
    units = param_units()
    rows = []
    for name in post.data_vars:
        arr = np.asarray(post[name])
        if arr.ndim != 2 or name not in units:
            continue  # per-protocol vectors and deterministics are in the idata file
        flat = arr.ravel()
        q05, q95 = np.percentile(flat, [5, 95])
        tv = (truth or {}).get(name)
        rows.append({"name": name, "unit": units[name], "mean": float(flat.mean()),
                     "sd": float(flat.std()), "q05": float(q05), "q95": float(q95),
                     "truth": float(tv) if isinstance(tv, (int, float)) else None})
    return rows


# keys of the resolved config that cannot change one law's fit: where files go, how the run
# is shown, which other laws run, how they are scheduled, the tension and the figures; the
# data enter through the digest of the model inputs. Every other key, present or future,
# enters the cache key.
_NOT_IN_FIT = ("out", "quiet", "laws", "workers", "data", "tension", "report")


def inputs_digest(inputs: dict[str, Any]) -> str:
    """sha256 of the model inputs (every array's dtype, shape and bytes; every scalar;
    nested tables key by key): what the processed data put into the model, whatever
    options processed them."""
    h = hashlib.sha256()

    def feed(v: Any) -> None:
        if isinstance(v, dict):
            for k in sorted(v):
                h.update(f"<{k}>".encode())
                feed(v[k])
        elif isinstance(v, (list, tuple)):
            h.update(f"[{len(v)}]".encode())
            for item in v:
                feed(item)
        elif v is None or isinstance(v, (bool, int, float, str)):
            h.update(repr(v).encode())
        else:
            a = np.ascontiguousarray(np.asarray(v))
            if a.dtype == object:  # no stable bytes: hash the elements
                feed(a.tolist())
                return
            h.update(f"{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())

    feed(inputs)
    return h.hexdigest()


@functools.cache
def code_digest(extra: tuple[str, ...] = ()) -> str:
    """sha256 of the code a fit runs: every file of the ``models`` and ``inference``
    packages (sources and tables) and the files ``extra`` (a law file's path), so that a
    resumed run does not reuse a fit made by other code under the same version."""
    from beadrod import inference, models
    h = hashlib.sha256()
    roots = [Path(models.__file__).parent, Path(inference.__file__).parent]
    files = [f for r in roots for f in sorted(r.rglob("*"))
             if f.is_file() and "__pycache__" not in f.parts]
    for f in files + [Path(e) for e in extra]:
        h.update(f"<{f.name}>".encode())
        h.update(f.read_bytes() if f.is_file() else b"missing")
    return h.hexdigest()


def _cache_key(name: str, spec: Any, cfg: dict[str, Any], inputs: dict[str, Any],
               data_hash: str) -> str:
    """What a cached fit must match to be reused: the whole ModelSpec (law, rung,
    likelihood, use_q, ...), every config key that can change the fit (sampling, evidence,
    seed, likelihood options, ...), the model inputs, the raw data hash, the version and
    the code (:func:`code_digest`, with the law's own file for a law file's law)."""
    from dataclasses import asdict

    from beadrod.inference.model.numpyro_models import law_of

    law = law_of(spec)
    source = (law.source,) if law is not None and law.source != "built-in" else ()
    blob = json.dumps({"law": name, "spec": asdict(spec),
                       "cfg": {k: v for k, v in cfg.items() if k not in _NOT_IN_FIT},
                       "inputs": inputs_digest(inputs), "data": data_hash,
                       "version": beadrod_version(), "code": code_digest(source)},
                      sort_keys=True, default=repr)
    return hashlib.sha256(blob.encode()).hexdigest()


def _cached(name: str, key: str, summary_path: Path, idata_path: Path) -> LawRun | None:
    """The finished fit in the output folder if its key is ``key`` and both its files
    read back; None otherwise (a truncated or foreign file is refitted, not an error)."""
    from beadrod.workflows.pipeline.idata_io import load_idata

    for path in (summary_path, idata_path):
        if path.exists() and not path.is_file():
            raise UserError(f"{path} is not a file: --resume reads a fit's summary and "
                            "InferenceData there; remove it or choose another --out")
    if not (summary_path.exists() and idata_path.exists()):
        return None
    try:
        cached = json.loads(summary_path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        log.warning("%s: %s is unreadable (%s); refitting", name, summary_path, exc)
        return None
    if not isinstance(cached, dict) or cached.get("cache_key") != key:
        log.info("%s: inputs changed since the cached fit; refitting", name)
        return None
    try:
        idata = load_idata(idata_path)
    except Exception as exc:  # noqa: BLE001 - netCDF/HDF5 raise many types on a bad file
        log.warning("%s: %s is unreadable (%s); refitting", name, idata_path, exc)
        return None
    return LawRun(name, cached, idata)


def fit_steps(cfg: dict[str, Any]) -> int:
    """Progress steps of one fit_law call: NUTS, diagnostics + LOO, one per estimator."""
    return 2 + len(cfg["evidence"]["methods"])


def fit_law(name: str, spec: Any, inputs: dict[str, Any], ds: Any, cfg: dict[str, Any],
            out: Path, *, resume: bool = False, job: str | None = None) -> LawRun:
    """NUTS + gate + LOO + evidence for one law; writes idata/NAME.nc and laws/NAME.json.

    An evidence estimator that fails (bridge sampling that does not converge, ...) marks
    the law FAILED with the reason and the fit is kept; the caller carries on. ``job``
    names the fit in the progress records (workflows.progress; default ``name``)."""
    from beadrod.inference.evidence.bridge import bridge_sampling_log_z
    from beadrod.inference.evidence.log_z import (
        combined_agreement,
        nested_sampling_log_z,
        smc_log_z,
    )
    from beadrod.inference.evidence.ranking import loo_pit_summary
    from beadrod.inference.model.numpyro_models import build_model
    from beadrod.inference.sampling import diagnostics
    from beadrod.inference.sampling.sample import run_nuts
    from beadrod.workflows.pipeline.idata_io import save_idata
    from beadrod.workflows.progress import begin, done

    job = job or name
    key = _cache_key(name, spec, cfg, inputs, ds.data_hash)
    summary_path = out / "laws" / f"{name}.json"
    idata_path = out / "idata" / f"{name}.nc"
    if resume:
        hit = _cached(name, key, summary_path, idata_path)
        if hit is not None:
            done(log, job, "%s: reusing the finished fit (inputs unchanged)", name,
                 steps=fit_steps(cfg), final=True)
            return hit

    s = cfg["sampling"]
    model = build_model(spec, scene=inputs.get("scene"))
    begin(log, job, "%s: NUTS (%d chains x %d warmup + %d draws), model %s", name,
          s["chains"], s["warmup"], s["samples"], spec.name)
    t0 = time.perf_counter()
    ess_min = diagnostics.gate_ess(s["samples"], s["chains"])
    fit = run_nuts(model, inputs, num_warmup=s["warmup"], num_samples=s["samples"],
                   num_chains=s["chains"], seed=cfg["seed"], target_accept=s["target_accept"],
                   data_hash=ds.data_hash, extra_attrs={"law": name},
                   coords={"protocol": list(ds.protocol_ids)}, ess_target=ess_min,
                   max_extensions=s["extensions"])
    timings = dict(fit.timings)
    modes = fit.modes.to_dict() if fit.modes is not None else None
    if modes and modes["gap"] is not None and modes["gap"] < MODE_GAP_WARN:
        log.warning("%s: a second posterior mode within %.1f nat of the one sampled: its "
                    "mass is missing from the evidence (bridge sampling fits one mode)",
                    name, modes["gap"])
    extensions = int(fit.idata.posterior.attrs.get("extensions", 0))
    if extensions:
        log.warning("%s: ESS below the gate's %.0f after %d draws per chain: the chains went "
                    "on %d time(s), %d draws per chain in all", name, ess_min, s["samples"],
                    extensions, s["samples"] * (1 + extensions))
    done(log, job, "%s: NUTS done (%.0f s)", name, time.perf_counter() - t0)
    begin(log, job, "%s: diagnostics and LOO", name)
    verdict = diagnostics.check(fit.idata, ess_min=ess_min)
    loo = diagnostics.loo_report(fit.idata)
    done(log, job, "%s: diagnostics %s", name, "passed" if verdict.passed else "FAILED")
    ev_cfg = cfg["evidence"]
    estimates, ev_failures = {}, []
    for method in ev_cfg["methods"]:  # in the order given: the first is the one that ranks
        try:
            if method == "ns":
                begin(log, job, "%s: evidence by nested sampling (%d live points)", name,
                      ev_cfg["live_points"])
                est = nested_sampling_log_z(model, {"data": inputs},
                                            num_live_points=ev_cfg["live_points"],
                                            seed=cfg["seed"])
            elif method == "bridge":
                begin(log, job, "%s: evidence by bridge sampling from the NUTS draws", name)
                est = bridge_sampling_log_z(model, {"data": inputs}, fit.idata,
                                            seed=cfg["seed"])
            else:
                begin(log, job, "%s: evidence by tempered SMC (%d particles x %d seeds)", name,
                      ev_cfg["smc_particles"], ev_cfg["smc_seeds"])
                seeds = tuple(range(cfg["seed"], cfg["seed"] + ev_cfg["smc_seeds"]))
                est = smc_log_z(model, {"data": inputs},
                                num_particles=ev_cfg["smc_particles"], seeds=seeds)
        except (RuntimeError, ValueError, FloatingPointError) as exc:
            # no evidence from this estimator: the law is FAILED, the comparison goes on
            ev_failures.append(f"evidence ({method}) failed: {exc}")
            log.error("%s: evidence by %s FAILED: %s", name, method, exc)
            done(log, job, "%s: evidence by %s failed", name, method)
            continue
        estimates[method] = est
        done(log, job, "%s: log Z = %.2f +- %.2f (%s, %.0f s)", name, est.log_z,
             est.log_z_err, method, est.wall_s)
    # a run that failed its gate is marked failed whatever its evidence: no fallback then
    fallback = _unreliable_bridge(estimates) if verdict.passed else ""
    if fallback and "ns" not in estimates:
        # one Normal proposal cannot bridge two modes: nested sampling, which needs none
        log.warning("%s: the bridge estimate is not reliable (%s): its evidence is taken "
                    "by nested sampling instead", name, fallback)
        begin(log, job, "%s: evidence by nested sampling (%d live points)", name,
              ev_cfg["live_points"])
        estimates["ns"] = nested_sampling_log_z(model, {"data": inputs},
                                                num_live_points=ev_cfg["live_points"],
                                                seed=cfg["seed"])
        done(log, job, "%s: log Z = %.2f +- %.2f (ns, %.0f s)", name, estimates["ns"].log_z,
             estimates["ns"].log_z_err, estimates["ns"].wall_s)
    for k, est in estimates.items():
        timings[f"evidence_{k}_s"] = est.wall_s
    timings["total_s"] = time.perf_counter() - t0
    # the first listed estimator ranks (nested sampling where the bridge is unreliable);
    # one that failed leaves log_z empty
    first = estimates.get("ns" if fallback else ev_cfg["methods"][0])
    second = next((estimates[m] for m in ev_cfg["methods"][1:2] if m in estimates), None)
    ests = list(estimates.values())
    agree = None
    if len(ests) >= 2:
        agree = all(combined_agreement(ests[0], e)[0] for e in ests[1:])
        if not agree:
            log.warning("%s: the two evidence estimators DISAGREE beyond their errors", name)
    failures = list(verdict.failures) + ev_failures
    summary = {
        "name": name, "label": model_labels().get(name, name), "model": spec.name,
        "rung": spec.rung,
        "status": "ok" if not failures else "failed", "failures": failures,
        "diagnostics": {"rhat_max": verdict.rhat_max, "ess_bulk_min": verdict.ess_bulk_min,
                        "ess_tail_min": verdict.ess_tail_min,
                        "divergences": verdict.divergences, "ebfmi_min": verdict.bfmi_min,
                        "extensions": extensions},
        "params": _param_summary(fit.idata, getattr(ds, "truth", None)),
        "log_z": first.log_z if first else None,
        "log_z_err": first.log_z_err if first else None,
        "log_z_method": first.method if first else None,
        "log_z2": second.log_z if second else None,
        "log_z2_err": second.log_z_err if second else None,
        "log_z2_method": second.method if second else None,
        "evidence_agree": agree, "evidence": {k: e.to_dict() for k, e in estimates.items()},
        "evidence_fallback": fallback or None,
        "observables": observed(spec, inputs),
        "elpd_loo": loo["elpd_loo"], "elpd_loo_se": loo["se"],
        "pareto_k_bad": loo["k_bad"] + loo["k_very_bad"], "loo": loo,
        "timings": timings, "modes": modes, "data_hash": ds.data_hash, "cache_key": key,
    }
    for key, site in (("loo_pit", "shift_obs"), ("loo_pit_amplitude", "amp_obs")):
        if site not in fit.idata.observed_data:
            continue
        try:  # the report's calibration check, here where the fit ran (a worker process)
            summary[key] = loo_pit_summary(fit.idata, site)
        except Exception as exc:  # noqa: BLE001 (a degenerate tiny run: say so, go on)
            summary[key] = {"error": f"{type(exc).__name__}: {exc}"}
    save_idata(fit.idata, idata_path)
    write_json(summary_path, summary)

    done(log, job, "%s: finished (%s, %.0f s)", name, "ok" if not failures else "FAILED",
         timings["total_s"], steps=0, final=True)
    return LawRun(name, summary, fit.idata)


def preferred_law(laws: list[dict[str, Any]]) -> tuple[str, str]:
    """Highest evidence among laws that passed their diagnostics (baseline excluded)."""
    ok = [r for r in laws if r["status"] == "ok" and r.get("log_z") is not None
          and r["name"] != "baseline"]
    if not ok:
        return "none", "no law passed its sampling diagnostics"
    from beadrod.workflows.report.tables import fmt_pm

    best = max(ok, key=lambda r: r["log_z"])
    others = sorted((r for r in ok if r is not best), key=lambda r: -r["log_z"])
    err = lambda *rs: float(np.hypot(*[r.get("log_z_err") or 0.0 for r in rs]))
    reason = f"highest log evidence ({fmt_pm(best['log_z'], best['log_z_err'])})"
    if others:
        d = best["log_z"] - others[0]["log_z"]
        reason += f", {fmt_pm(d, err(best, others[0]))} nats above {others[0]['label']}"
    base = next((r for r in laws if r["name"] == "baseline" and r.get("log_z") is not None), None)
    if base is not None and base["log_z"] > best["log_z"]:
        lead = fmt_pm(base["log_z"] - best["log_z"], err(base, best))
        reason += (f"; but the law-free baseline beats it by {lead}"
                   " nats: no contact law captures the shape of the data")
    return best["name"], reason


# the law-free baseline's fit time on the scale of models.law.SamplerHints.cost (measured on
# the embedded data: below the table-driven adhesive laws, above the closed-form ones)
BASELINE_COST = 1.5


def job_order(job: Any) -> tuple[float, int]:
    """Sort key of a workflows.pipeline.parallel.Job: the costliest first, so that the last job to
    finish is a short one. A fit or evidence job costs its law's ``cost`` (the baseline
    :data:`BASELINE_COST`); among equal costs the tension's Eq. 25 fits go first (they
    are the slower), and jobs of no law (the tension's extra draws) run last."""
    from beadrod.inference.model.numpyro_models import BASELINE
    from beadrod.models.registry import get_law, law_names

    law = getattr(job.spec, "law", None)  # a ModelSpec; the extra draws carry keywords
    if law == BASELINE:
        cost = BASELINE_COST
    elif law in law_names():
        cost = get_law(law).sampler.cost
    else:
        return (0.0, 2)
    return (-cost, int(not job.key.startswith("tension:")))
