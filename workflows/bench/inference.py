"""``beadrod bench inference``: NUTS per law on the embedded dataset, and the baseline.

For each law of the default comparison, and each other built-in law with a fast backbone
(fitted by name: Maugis-Dugdale): compile time (a 1+1-iteration run of the same
kernel) apart from sampling time, the smallest bulk ESS over the scalar
parameters, ESS per second of sampling, and the evidence by both estimators
with its wall time. Because a fast law's sampling can take less time than the noise of its
compile probe, sampling is also measured without the probe: ESS per second of sampling
work, the draws' leapfrog steps times the cost of one step inside NUTS, timed on a
compiled one-chain loop of post-warmup draws (:func:`inference.sampling.sample.draw_program`),
every model's loop timed in turns after all the fits, the median of seven interleaved
rounds with its spread ((max - min)/median, column ``step_spread``), so that neither the
machine's drift over the run nor one busy moment enters the ratios; the laws are compared
with Hertz both ways. NUTS runs with fixed seeds, so its ESS and step counts repeat from
run to run and only the step costs vary.

The baseline is what a physicist would write without this project: the same
Hertz posterior (first-order shift, per-protocol overlap conditioned on the
measured f0, one Gaussian sd for every shift) as a plain NumPy log-density for
``emcee``, the shift computed per sweep with ``scipy.integrate.quad`` of the paper's
Eq. 23. Before timing, the
baseline log-density is checked against NumPyro's on random parameter draws
(the difference must be one constant): the two samplers target the same
posterior or the comparison is refused.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from beadrod.data.io import write_text

__all__ = ["run", "baseline_log_density", "timed_nuts", "results_markdown",
           "step_time_summary"]

_G = 9.80665
_ROUNDS = 7   # rounds of the step-cost loops, every model once a round (median, spread)


def _paper_eq23(x: float) -> float:
    """(1/4 pi) Int_0^2pi (1 + x sin t)^(1/2) dt - 1/2 by adaptive quadrature (clipped)."""
    from scipy.integrate import quad

    val, _ = quad(lambda t: np.sqrt(max(1.0 + x * np.sin(t), 0.0)), 0.0, 2 * np.pi,
                  epsabs=1e-12, epsrel=1e-10, limit=200)
    return val / (4 * np.pi) - 0.5


def baseline_log_density(theta: np.ndarray, d: dict[str, Any]) -> float:
    """log prior + log likelihood of the Hertz model, written from scratch in NumPy.

    theta = (young [Pa], delta0_scatter, sigma_shift, offset_down, mu_logq, tau_logq).
    """
    from scipy import stats

    young, scatter, sig, off, mu_q, tau_q = theta
    if not (150e9 < young < 250e9) or scatter <= 0 or sig <= 0 or tau_q <= 0:
        return -np.inf
    lp = (-np.log(100e9) + stats.halfnorm.logpdf(scatter, scale=0.3)
          + stats.halfnorm.logpdf(sig, scale=0.01) + stats.norm.logpdf(off, 0, 0.005)
          + stats.norm.logpdf(mu_q, np.log(50.0), 1.5) + stats.halfnorm.logpdf(tau_q, scale=1.0))
    e_star = young / (2 * (1 - d["nu"] ** 2))
    d0_ref = (3 * d["load"] / (4 * e_star * np.sqrt(d["radius"]))) ** (2 / 3)
    omega = 2 * np.pi * d["f0"]
    d0 = 1.5 * d["load"] / (d["mass"] * omega**2)
    lp += np.sum(stats.norm.logpdf(np.log(d0), np.log(d0_ref), scatter) + np.log(2 / d["f0"]))
    x = d["amplitude"] / d0[d["proto"]]
    pred = np.array([_paper_eq23(xi) for xi in x]) + off * d["direction"]
    lp += np.sum(stats.norm.logpdf(d["shift"], pred, sig))
    lp += np.sum(stats.lognorm.logpdf(d["q_obs"], s=tau_q, scale=np.exp(mu_q)))
    return float(lp)


def _numpy_inputs(inputs: dict[str, Any]) -> dict[str, Any]:
    return {"f0": np.asarray(inputs["f0"]), "amplitude": np.asarray(inputs["amplitude"]),
            "proto": np.asarray(inputs["proto"]), "direction": np.asarray(inputs["direction"]),
            "shift": np.asarray(inputs["shift"]), "q_obs": np.asarray(inputs["q_obs"]),
            "load": inputs["load"], "mass": inputs["mass"], "radius": inputs["radius"],
            "nu": inputs["nu_bead"]}


_BASE_NAMES = ("young", "delta0_scatter", "sigma_shift", "offset_down", "mu_logq", "tau_logq")


def _check_same_posterior(model, inputs, d, rng) -> float:
    """Max spread of (numpyro log joint - baseline log joint) over random draws."""
    from numpyro.infer.util import log_density

    diffs = []
    for _ in range(4):
        theta = np.array([rng.uniform(185e9, 215e9), rng.uniform(0.02, 0.2),
                          rng.uniform(0.005, 0.02), rng.normal(0, 0.003),
                          rng.normal(np.log(50), 0.3), rng.uniform(0.3, 0.8)])
        params = dict(zip(_BASE_NAMES, theta))
        lj, _ = log_density(model, (inputs,), {}, params)
        diffs.append(float(lj) - baseline_log_density(theta, d))
    return float(np.ptp(diffs))


def _min_ess(idata, names) -> float:
    import arviz as az

    ess = az.ess(idata, var_names=[n for n in names if n in idata.posterior], method="bulk")
    return float(min(float(np.min(np.asarray(ess[v]))) for v in ess.data_vars))


def timed_nuts(model, inputs: dict[str, Any], chains: int, warm: int, draws: int,
               chain_method: str | None = None) -> tuple[Any, float, float, float]:
    """NUTS with compilation measured apart: (fit, compile s, sampling s, smallest bulk
    ESS over the scalar parameters). Sampling is NaN where the 1+1-iteration compile probe
    took (nearly) as long as the whole run: too short to separate."""
    from beadrod.inference.sampling.sample import run_nuts
    from beadrod.workflows.pipeline.fits import PARAM_UNITS

    fit = run_nuts(model, inputs, num_warmup=warm, num_samples=draws, num_chains=chains,
                   seed=0, predictive=False, measure_compile=True, chain_method=chain_method)
    t = fit.timings
    sampling = t["nuts_s"] - t["compile_s"]
    if not sampling > 0.05 * t["nuts_s"]:
        sampling = float("nan")
    ess = _min_ess(fit.idata, [v for v in fit.idata.posterior.data_vars if v in PARAM_UNITS])
    return fit, t["compile_s"], sampling, ess


def step_time_summary(times: list[float]) -> tuple[float, float]:
    """(median, relative spread) of one loop's times over the interleaved rounds: the
    spread is (max - min) / median, so a round that caught the machine busy shows."""
    t = np.asarray(times, float)
    med = float(np.median(t))
    return med, float((t.max() - t.min()) / med)


def _run_emcee(d, n_walkers: int, n_steps: int, seed: int):
    import emcee

    rng = np.random.default_rng(seed)
    p0 = np.column_stack([rng.uniform(195e9, 205e9, n_walkers), rng.uniform(0.05, 0.1, n_walkers),
                          rng.uniform(0.005, 0.01, n_walkers), rng.normal(0, 1e-3, n_walkers),
                          rng.normal(np.log(50), 0.1, n_walkers), rng.uniform(0.4, 0.6, n_walkers)])
    sampler = emcee.EnsembleSampler(n_walkers, 6, baseline_log_density, args=(d,))
    t0 = time.perf_counter()
    sampler.run_mcmc(p0, n_steps, progress=False)
    wall = time.perf_counter() - t0
    chain = sampler.get_chain(discard=n_steps // 2)
    tau = emcee.autocorr.integrated_time(chain, tol=0)
    ess = chain.shape[0] * chain.shape[1] / tau
    return wall, float(np.min(ess)), tau


def _ratios(rows: list[dict[str, Any]], specs: dict[str, Any]) -> str:
    """Each backbone model's ESS/s as a fraction of Hertz's, two ways: sampling alone
    (ESS per second of sampling work: the draws' leapfrog steps times the measured cost of
    one step inside NUTS, which no compilation enters) and the whole NUTS run with its
    compilation."""
    ref = next((r for r in rows if r["model"] == "hertz"), None)
    if ref is None:
        return ""
    lines = ["ESS/s as a fraction of Hertz's (target for the rough-contact and adhesion "
             "laws: >= 1/3). Sampling alone = ESS per second of sampling work (leapfrog "
             "steps of the draws x the cost of one step inside NUTS, timed on a compiled "
             "one-chain loop of post-warmup draws); with compilation = ESS over the whole "
             "NUTS wall time:", ""]
    for r in rows:
        if r["model"] not in specs or r["model"] == "hertz" or "ess_per_step_s" not in r:
            continue
        a = r["ess_per_step_s"] / ref["ess_per_step_s"]
        b = r["ess_per_s_incl_compile"] / ref["ess_per_s_incl_compile"]
        mark = lambda v: "below 1/3" if v < 1 / 3 else "ok"
        lines.append(f"- {r['model']}: sampling alone **{a:.2f}** ({mark(a)}), with "
                     f"compilation **{b:.2f}** ({mark(b)}); {r['us_per_step']:.1f} us "
                     f"per step (spread {r.get('step_spread', float('nan')):.0%}) against "
                     f"{ref['us_per_step']:.1f} ({ref.get('step_spread', float('nan')):.0%}), "
                     f"{r['gradients_per_draw']:.1f} steps per draw against "
                     f"{ref['gradients_per_draw']:.1f}")
    return "\n".join(lines)


def results_markdown(table) -> str:
    from beadrod.workflows.report.document import markdown_table

    def cell(v: Any) -> str:
        if v is None or (isinstance(v, float) and not np.isfinite(v)):
            return "-"
        return f"{v:.4g}" if isinstance(v, (float, np.floating)) else str(v)

    return markdown_table(list(table.columns), [[cell(v) for v in row] for row in
                                           table.itertuples(index=False)])


def _bench_names(default: list[str]) -> list[str]:
    """The default comparison's models, then the built-in laws it leaves out that have a
    fast backbone (their speed is what keeps them out: the benchmark measures it)."""
    from beadrod.inference.model.numpyro_models import BASELINE
    from beadrod.models.registry import laws

    extra = [law.name for law in laws() if law.name not in default and law.source == "built-in"
             and "backbone" in law.physics.rungs and not law.too_slow_for_nuts("backbone")]
    return [n for n in default if n != BASELINE] + extra + [n for n in default if n == BASELINE]


def run(out_dir: Path, quick: bool = False) -> Path:
    """Measure and write ``bench_inference.csv`` / ``.md`` into ``out_dir``; return the .md."""
    import jax

    from beadrod.inference.evidence.bridge import bridge_sampling_log_z
    from beadrod.inference.model.likelihood import model_inputs
    from beadrod.inference.model.numpyro_models import ModelSpec, build_model
    from beadrod.inference.sampling.sample import draw_program
    from beadrod.workflows.config import DEFAULTS, merge
    from beadrod.workflows.pipeline.fits import (
        comparison_specs,
        default_model_names,
        job_order,
        load_data,
    )
    from beadrod.workflows.pipeline.parallel import Job, resolve_workers, run_jobs
    from beadrod.workflows.pipeline.run import JOBS

    out_dir = Path(out_dir)
    chains, warm, draws = (2, 30, 30) if quick else (4, 400, 400)
    live = 30 if quick else DEFAULTS["evidence"]["live_points"]  # what compare uses
    cfg = merge(DEFAULTS, {"evidence": {"live_points": live}})
    ds = load_data(cfg)  # the embedded dataset, as compare loads it
    inputs = model_inputs(ds)
    rows = []
    names = ["hertz"] if quick else _bench_names(default_model_names())
    specs = comparison_specs(names, "backbone", "normal")
    # nested sampling of every model as compare runs it: side by side in worker processes
    ns_jobs = sorted((Job(k, "ns", k, v, cfg) for k, v in specs.items()), key=job_order)
    workers = resolve_workers(cfg["workers"], len(ns_jobs))
    t0 = time.perf_counter()
    ns_all = run_jobs(ns_jobs, runner=JOBS, workers=workers, ds=ds, inputs=inputs,
                      resume=False, n_devices=chains)
    t_ns_wall = time.perf_counter() - t0
    # the emcee baseline's model: one Gaussian sd for every shift, as written by hand
    specs["hertz_first_order"] = ModelSpec(law="hertz", rung="first_order",
                                           shift_noise="constant")
    t_bridge = 0.0
    loops: dict[str, tuple] = {}
    for name, spec in specs.items():
        model = build_model(spec)
        fit, compile_s, sampling, ess = timed_nuts(model, inputs, chains, warm, draws)
        ns = br = None
        if name != "hertz_first_order":
            ns = ns_all[name]
            br = bridge_sampling_log_z(model, {"data": inputs}, fit.idata)
            t_bridge += br.wall_s
        init = None if fit.modes is None else fit.modes.best
        loops[name] = draw_program(model, inputs, init_params=init, num_warmup=warm // 2,
                                   num_draws=draws // 2)
        steps = np.asarray(fit.idata.sample_stats["n_steps"])
        grads = float(np.sum(steps))
        rows.append({"model": name, "rung": spec.rung, "compile_s": compile_s,
                     "mode_search_s": fit.timings.get("mode_search_s"),
                     "sampling_s": sampling, "min_bulk_ess": ess, "ess_per_s": ess / sampling,
                     "ess_per_s_incl_compile": ess / fit.timings["nuts_s"],
                     "us_per_step": None,          # timed below, all models in turns
                     "gradients_per_draw": grads / steps.size,
                     "ess_per_step_s": None,
                     "log_z_ns": ns.log_z if ns else None, "err_ns": ns.log_z_err if ns else None,
                     "ns_s": ns.wall_s if ns else None,
                     "log_z_bridge": br.log_z if br else None,
                     "err_bridge": br.log_z_err if br else None,
                     "bridge_s": br.wall_s if br else None})
    # the step costs timed in turns, every model's loop once a round, the median of
    # ROUNDS: timed right after each fit, minutes apart, they would take the machine's
    # drift with them; a best-of kept one lucky round
    times: dict[str, list[float]] = {k: [] for k in loops}
    for _ in range(_ROUNDS):
        for k, (run_loop, _) in loops.items():
            times[k].append(run_loop())
    for r in rows:
        if r["model"] in loops:
            med, spread = step_time_summary(times[r["model"]])
            step_s = med / (draws // 2) / loops[r["model"]][1]
            grads = r["gradients_per_draw"] * chains * draws
            r["us_per_step"] = 1e6 * step_s
            r["step_spread"] = spread
            r["ess_per_step_s"] = r["min_bulk_ess"] / (grads * step_s)
    # the baseline, on the same posterior as hertz_first_order
    d = _numpy_inputs(inputs)
    spread = _check_same_posterior(build_model(specs["hertz_first_order"]), inputs, d,
                                   np.random.default_rng(0))
    if spread > 1e-6 * max(1.0, abs(baseline_log_density(
            np.array([2e11, 0.1, 0.01, 0.0, np.log(50), 0.5]), d))):
        raise RuntimeError(f"baseline and NumPyro log densities differ by a non-constant "
                           f"({spread:.3g}): they do not target the same posterior")
    walkers, steps = (16, 20) if quick else (24, 300)
    wall, ess_b, _tau = _run_emcee(d, walkers, steps, seed=0)
    rows.append({"model": "baseline: emcee + scipy quad (hertz, first order)",
                 "rung": "first_order", "compile_s": 0.0, "sampling_s": wall,
                 "min_bulk_ess": ess_b, "ess_per_s": ess_b / wall})
    nuts_fo = next(r for r in rows if r["model"] == "hertz_first_order")
    ratio = nuts_fo["ess_per_s"] / rows[-1]["ess_per_s"]
    if np.isfinite(ratio):
        speedup = f"**{ratio:.0f}x**"
    elif np.isfinite(low := nuts_fo["ess_per_s_incl_compile"] / rows[-1]["ess_per_s"]):
        # sampling too short to separate from compilation: a lower bound instead
        speedup = (f"at least **{low:.3g}x** (compilation included: the sampling alone was "
                   "too short to separate from the compile probe)")
    else:
        speedup = ("not measured (the run is too short to estimate the emcee baseline's "
                   "ESS)")
    clash = [f"{r['model']} ({r['log_z_ns']:.2f} ± {r['err_ns']:.2f} against "
             f"{r['log_z_bridge']:.2f} ± {r['err_bridge']:.2f})" for r in rows
             if r.get("log_z_ns") is not None and r.get("log_z_bridge") is not None
             and abs(r["log_z_ns"] - r["log_z_bridge"])
             > 3.0 * np.hypot(r["err_ns"], r["err_bridge"])]
    import pandas as pd

    ratios = _ratios(rows, specs)
    table = pd.DataFrame(rows)
    write_text(out_dir / "bench_inference.csv", table.to_csv(index=False))
    md = ["# Inference benchmark (embedded paper_like dataset, "
          f"{ds.n_protocols} protocols, {ds.n_drive} drive sweeps)", "",
          f"Device: {jax.devices()[0].platform}, {jax.local_device_count()} host device(s); "
          f"NUTS {chains} chains x {warm} warmup + {draws} draws; evidence: nested sampling "
          f"{live} live points, bridge sampling from the NUTS draws; "
          f"emcee {walkers} walkers x {steps} steps (ESS from the integrated autocorrelation "
          "time of the second half). Compile time is a 1+1-iteration run of the same kernel; "
          "mode_search_s, the multi-start search that places the chains "
          "(inference.sampling.modes), "
          "compilation included, comes before both and is in neither.",
          "", results_markdown(table), "",
          f"NUTS (hertz, first order) ESS/s over the emcee + quad baseline on the same "
          f"posterior: {speedup} (target >= 100x); log-density agreement spread "
          f"{spread:.2e}. Evidence for all {len(ns_jobs)} models by bridge sampling (the "
          f"default estimator): **{t_bridge:.0f} s** (target < 120 s); the nested-sampling "
          f"cross-check (`--evidence bridge,ns`) adds {t_ns_wall:.0f} s wall in {workers} "
          f"worker process(es) (sum of the per-model times "
          f"{sum(r.wall_s for r in ns_all.values()):.0f} s; each includes its compilation): "
          f"both together {t_ns_wall + t_bridge:.0f} s."
          + (" The two estimators DISAGREE beyond 3 sigma for: " + "; ".join(clash) + "."
             if clash else " The two estimators agree within 3 sigma for every model.")
          + (" QUICK RUN: numbers not meaningful." if quick else ""), "", ratios]
    return write_text(out_dir / "bench_inference.md", "\n".join(md) + "\n")
