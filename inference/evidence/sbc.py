"""Simulation-based calibration (Talts et al. 2018, arXiv:1804.06788).

For each replicate: draw parameters from the prior, simulate data on a fixed design
from the model itself, fit by NUTS, and record the rank of the true value among L
(thinned) posterior draws. A calibrated inference gives ranks uniform on {0, ..., L}.

Uniformity test: the randomised PIT u = (rank + U(0, 1)) / (L + 1) is exactly
Uniform(0, 1) under calibration; a Kolmogorov-Smirnov test of u gives a p-value per
parameter (Säilynoja, Bürkner & Vehtari 2022 use the same ECDF). :func:`ecdf_difference`
gives the ECDF - uniform curve per parameter and the simultaneous (1 - alpha) band of the
Dvoretzky-Kiefer-Wolfowitz inequality, eps = sqrt(ln(2/alpha) / (2 N)) (Massart 1990),
as arrays; workflows.pipeline.sbc_outputs plots and writes them (inference writes no files).

One MCMC object with ``jit_model_args=True`` serves every replicate (same shapes), so
the sampler compiles once.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from numpyro.infer import MCMC, NUTS, Predictive, init_to_median
from scipy import stats

from beadrod.inference.model.likelihood import design_inputs, without_observations  # noqa: F401  (re-export)
from beadrod.inference.model.numpyro_models import ModelSpec, build_model

__all__ = ["SBCResult", "run_sbc", "uniformity_pvalue", "dkw_halfwidth",
           "ecdf_difference"]


@dataclass
class SBCResult:
    """Ranks (replicates,) per parameter out of ``n_draws`` posterior draws."""

    ranks: dict[str, np.ndarray]
    n_draws: int
    pvalues: dict[str, float]
    wall_s: float
    divergences: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def min_pvalue(self) -> float:
        return float(min(self.pvalues.values()))


def uniformity_pvalue(ranks: np.ndarray, n_draws: int, seed: int = 0) -> float:
    """KS p-value of the randomised PIT (rank + U)/(n_draws + 1) against Uniform(0, 1)."""
    ranks = np.asarray(ranks, float)
    u = (ranks + np.random.default_rng(seed).uniform(size=ranks.shape)) / (n_draws + 1)
    return float(stats.kstest(u, "uniform").pvalue)


def _scalar_sites(samples: dict[str, Any], params: tuple[str, ...] | None) -> list[str]:
    if params is not None:
        return list(params)
    return [k for k, v in samples.items() if np.ndim(v) == 1]


def run_sbc(
    spec: ModelSpec,
    design: dict[str, Any],
    *,
    n_replicates: int = 20,
    num_warmup: int = 300,
    num_samples: int = 300,
    thin: int = 3,
    seed: int = 0,
    params: tuple[str, ...] | None = None,
) -> SBCResult:
    """SBC of ``spec`` on ``design`` (:func:`inference.model.likelihood.design_inputs`).

    ``params``: scalar latent sites to rank (default: every scalar latent site).
    ``thin`` reduces autocorrelation of the draws (ranks need near-independent draws).
    """
    model = build_model(spec, n_protocols=design["n_protocols"])
    key = jax.random.PRNGKey(seed)
    k_prior, k_fit = jax.random.split(key)
    t0 = time.perf_counter()
    prior = Predictive(model, num_samples=n_replicates)(k_prior, design)
    latent = [k for k in prior if k not in ("f0_obs", "shift_obs", "q_obs")]
    names = _scalar_sites({k: prior[k] for k in latent
                           if k not in ("delta0", "f0_pred", "shift_pred", "q_pred",
                                        "e_star")}, params)
    kernel = NUTS(model, target_accept_prob=0.9, dense_mass=True,
                  init_strategy=init_to_median(num_samples=15))
    # progress_bar=True is numpyro 0.22's path that keeps the compiled sampler between
    # run() calls (with False it recompiles every replicate); the bar goes to stderr
    mcmc = MCMC(kernel, num_warmup=num_warmup, num_samples=num_samples * thin, num_chains=1,
                progress_bar=True, jit_model_args=True)
    ranks = {k: np.zeros(n_replicates, int) for k in names}
    divs = np.zeros(n_replicates, int)
    base = {k: v for k, v in design.items() if k != "n_protocols"}
    for r in range(n_replicates):
        data = dict(base)
        data["f0"] = prior["f0_obs"][r]
        if "shift_obs" in prior:
            data["shift"] = prior["shift_obs"][r]
        if "q_obs" in prior:
            data["q_obs"] = prior["q_obs"][r]
        mcmc.run(jax.random.fold_in(k_fit, r), data, extra_fields=("diverging",))
        post = mcmc.get_samples()
        divs[r] = int(jnp.sum(mcmc.get_extra_fields()["diverging"]))
        for k in names:
            draws = np.asarray(post[k])[::thin]
            ranks[k][r] = int(np.sum(draws < np.asarray(prior[k][r])))
    pvals = {k: uniformity_pvalue(v, num_samples, seed) for k, v in ranks.items()}
    return SBCResult(ranks, num_samples, pvals, time.perf_counter() - t0, divs)


def dkw_halfwidth(n: int, alpha: float = 0.05) -> float:
    """Half-width eps of the DKW band: P(sup |ECDF_n - F| > eps) <= alpha for n draws,
    eps = sqrt(ln(2/alpha) / (2 n)) (Massart 1990's tight constant)."""
    if n < 1 or not 0.0 < alpha < 1.0:
        raise ValueError(f"need n >= 1 and 0 < alpha < 1, got n={n}, alpha={alpha}")
    return float(np.sqrt(np.log(2.0 / alpha) / (2.0 * n)))


def ecdf_difference(result: SBCResult, grid: np.ndarray | None = None,
                    alpha: float = 0.05) -> tuple[np.ndarray, dict[str, np.ndarray], float]:
    """(grid, {param: ECDF(u) - grid}, DKW half-width) of the fractional ranks
    u = (rank + 1/2) / (L + 1) on ``grid`` in [0, 1] (default 201 points)."""
    grid = np.linspace(0.0, 1.0, 201) if grid is None else np.asarray(grid, float)
    out = {}
    n = 0
    for k, r in result.ranks.items():
        u = np.sort((np.asarray(r, float) + 0.5) / (result.n_draws + 1))
        n = len(u)
        out[k] = np.searchsorted(u, grid, side="right") / n - grid
    return grid, out, dkw_halfwidth(max(n, 1), alpha)
