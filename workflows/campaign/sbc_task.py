"""One SBC replicate, as a Dask worker runs it (Talts et al. 2018; Modrák et al. 2023).

Draw a truth from the prior and a dataset from the model at that truth on the task's
fixed design (one prior-predictive draw), fit it by NUTS, and record the rank of every
scalar latent parameter's truth among the kept posterior draws, and the rank of the
data's log-likelihood at the truth among its values at the draws: a test quantity that
depends on the data as well as the parameters, which sees miscalibration the marginal
ranks can miss (Modrák et al. 2023). Every replicate's gate (R-hat, ESS, divergences,
E-BFMI; inference.sampling.diagnostics.check) is recorded, so that replicates which fail
it are counted, not dropped.

A worker keeps one NUTS sampler per (model, design, sampling options) for all the
replicates it runs: the model's inputs are arguments of the compiled program
(``jit_model_args``), so a worker compiles once and each later replicate only samples, as
inference.evidence.sbc.run_sbc does in one process. The chains start at the prior median
(numpyro's init_to_median), as run_sbc's do; ``compare`` starts them at a mode search's
best mode, which SBC would have to redo for every replicate.
"""

from __future__ import annotations

import json
import logging
import time
import warnings
from typing import Any

import numpy as np

__all__ = ["run_sbc_task", "LOGLIK"]

LOGLIK = "log_lik"
"""The name of the log-likelihood test quantity among a replicate's ranks."""

_OBS = (("f0_obs", "f0"), ("shift_obs", "shift"), ("q_obs", "q_obs"), ("amp_obs", "amp_obs"))

# per worker process: (model, MCMC, latent sites, jitted log-likelihood, design inputs)
_SAMPLERS: dict[str, tuple[Any, ...]] = {}


def _sampler(inputs: dict[str, Any]) -> tuple[Any, ...]:
    import jax
    import jax.numpy as jnp
    from numpyro.infer import MCMC, NUTS, Predictive, init_to_median
    from numpyro.infer.util import log_likelihood

    from beadrod.inference.evidence.log_z import latent_site_names
    from beadrod.inference.model.numpyro_models import ModelSpec, build_model
    from beadrod.workflows.campaign.tasks import sbc_design_inputs

    key = json.dumps({k: inputs[k] for k in ("spec", "design", "sampling", "thin")},
                     sort_keys=True)
    if key in _SAMPLERS:
        return _SAMPLERS[key]
    s = inputs["sampling"]
    design = sbc_design_inputs(inputs["design"])
    model = build_model(ModelSpec(**inputs["spec"]), n_protocols=design["n_protocols"])
    kernel = NUTS(model, target_accept_prob=float(s.get("target_accept", 0.9)),
                  dense_mass=True, init_strategy=init_to_median(num_samples=15))
    # progress_bar=True is numpyro 0.22's path that keeps the compiled sampler between
    # run() calls (with False every run recompiles); the workers hide the bar
    # (TQDM_DISABLE, workflows.campaign.engine)
    mcmc = MCMC(kernel, num_warmup=int(s["warmup"]),
                num_samples=int(s["samples"]) * int(inputs["thin"]),
                num_chains=int(s["chains"]), chain_method="sequential", progress_bar=True,
                jit_model_args=True)
    prior = Predictive(model, num_samples=1)(jax.random.PRNGKey(0), design)
    data = _observed(design, prior)
    latents = latent_site_names(model, {"data": data})

    @jax.jit
    def loglik(samples: dict[str, Any], data: dict[str, Any]) -> Any:
        ll = log_likelihood(model, samples, data)
        return sum(jnp.sum(jnp.reshape(v, (v.shape[0], -1)), axis=1) for v in ll.values())

    _SAMPLERS[key] = (model, mcmc, latents, loglik, design)
    return _SAMPLERS[key]


def _observed(design: dict[str, Any], prior: dict[str, Any]) -> dict[str, Any]:
    # the design with the first prior-predictive draw's observations filled in
    data = {k: v for k, v in design.items() if k != "n_protocols"}
    for site, name in _OBS:
        if site in prior:
            data[name] = prior[site][0]
    return data


def _gate(samples: dict[str, Any], extra: dict[str, Any], n_kept: int,
          chains: int) -> dict[str, Any]:
    """The comparison's gate on the kept draws (inference.sampling.diagnostics.check),
    without its log line and warning: the campaign's summary counts the failures."""
    import arviz as az

    from beadrod.inference.sampling import diagnostics

    post = {k: np.asarray(v) for k, v in samples.items()}
    stats = {k: np.asarray(extra[k]) for k in ("diverging", "energy") if k in extra}
    idata = az.from_dict(posterior=post, sample_stats=stats)
    log = logging.getLogger("beadrod.inference")
    was = log.disabled
    log.disabled = True
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            v = diagnostics.check(idata, ess_min=diagnostics.gate_ess(n_kept, chains))
    finally:
        log.disabled = was
    return {"status": "ok" if v.passed else "failed", "failures": list(v.failures),
            "rhat_max": v.rhat_max, "ess_bulk_min": v.ess_bulk_min,
            "ess_tail_min": v.ess_tail_min, "divergences": int(v.divergences),
            "ebfmi_min": v.bfmi_min}


def run_sbc_task(inputs: dict[str, Any]) -> dict[str, Any]:
    """The result of one SBC replicate (workflows.campaign.tasks.sbc_tasks's inputs):
    ranks per parameter and of the log-likelihood (:data:`LOGLIK`) out of ``n_draws``,
    the truth (sample-site values), the gate, and the timings."""
    import jax
    import jax.numpy as jnp
    from numpyro.infer import Predictive

    t0 = time.perf_counter()
    model, mcmc, latents, loglik, design = _sampler(inputs)
    t_ready = time.perf_counter()
    key = jax.random.fold_in(jax.random.PRNGKey(int(inputs["seed"])), int(inputs["replicate"]))
    k_prior, k_fit = jax.random.split(key)
    prior = Predictive(model, num_samples=1)(k_prior, design)
    data = _observed(design, prior)
    t_sim = time.perf_counter()
    mcmc.run(k_fit, data, extra_fields=("diverging", "energy"))
    thin = int(inputs["thin"])
    samples = {k: np.asarray(v)[:, ::thin] for k, v in
               mcmc.get_samples(group_by_chain=True).items()}
    extra = {k: np.asarray(v)[:, ::thin] for k, v in
             mcmc.get_extra_fields(group_by_chain=True).items()}
    t_fit = time.perf_counter()
    chains, kept = np.shape(samples[latents[0]])[:2]
    values = {k: np.asarray(prior[k][0]) for k in latents}
    scalar = [k for k in latents if values[k].ndim == 0]  # the ranked parameters
    truth = {k: float(values[k]) for k in scalar}
    ranks = {k: int(np.sum(samples[k].ravel() < truth[k])) for k in scalar}
    # the log-likelihood of the data at every kept draw and at the truth, one program
    flat = {k: jnp.asarray(np.concatenate([
        np.reshape(samples[k], (chains * kept, *values[k].shape)), values[k][None]]))
        for k in latents}
    ll = np.asarray(loglik(flat, data))
    ranks[LOGLIK] = int(np.sum(ll[:-1] < ll[-1]))
    gate = _gate(samples, extra, int(kept), int(chains))
    t_end = time.perf_counter()
    return {"ranks": ranks, "n_draws": int(chains * kept), "truth": truth,
            "log_lik_truth": float(ll[-1]), "gate": gate,
            "timings": {"setup_s": t_ready - t0, "simulate_s": t_sim - t_ready,
                        "fit_s": t_fit - t_sim, "ranks_s": t_end - t_fit,
                        "total_s": t_end - t0}}
