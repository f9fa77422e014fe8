"""log Z by plain importance sampling from a Student-t fitted to the NUTS draws.

The third estimator, which decides when bridge sampling and nested sampling disagree. It
is deliberately the simplest unbiased estimator of Z there is (Geweke 1989, "Bayesian
inference in econometric models using Monte Carlo integration", Econometrica 57, 1317),
so that its correctness can be seen at a glance:

1. Map all posterior draws to numpyro's unconstrained space u (where the unnormalised
   posterior is q(u) = exp(-potential_energy(u)) and Z = integral q(u) du) and take
   their sample mean m and covariance C.
2. Proposal g = multivariate Student-t with ``df`` degrees of freedom (5), location m
   and scale matrix C. Its covariance is C df/(df - 2): the draws' covariance inflated
   by 5/3 (29 % in sd). Why a t and why that much: the variance of the estimate is
   finite only when q/g is square-integrable under g, i.e. when g's tails are heavier
   than the posterior's. A t5 decays polynomially, so q/g stays bounded for any
   posterior with Gaussian or lighter tails in u, and the wider bulk covers the error of
   the sample moments and mild skewness. More inflation costs efficiency that
   compounds with the dimension d: for a Gaussian target and a Gaussian proposal whose
   variance is s^2 times the target's in every direction, the sample size needed for a
   given error grows by (s^2/sqrt(2 s^2 - 1))^d, 1.09^d at s^2 = 5/3 but 1.20^d at
   s^2 = 9/4 (3.1 against 11 at d = 13).
3. Draw N points u_j from g (independent of each other; g depends on the posterior
   draws only through m and C, and the estimate is unbiased for any fixed g), and with
   log w_j = log q(u_j) - log g(u_j)::

       log Z = logsumexp(log w) - log N.

4. Error (delta method): Var(Z_hat) = Var(w)/N, so the 1-sigma error of log Z is
   sd(w) / (sqrt(N) mean(w)), the relative error of Z_hat.

``settings`` carries the Pareto k-hat of the weights (``pareto_k``, ``arviz.psislw``;
Vehtari, Simpson, Gelman, Yao & Gabry 2024) with its threshold min(1 - 1/log10(N), 0.7),
the weights' effective sample size (sum w)^2 / sum w^2, the number of proposal draws
where log q is not finite (``zero_weights``: counted as w = 0, as bridge sampling does),
and ``reliable`` / ``reason``: unreliable when k-hat exceeds the threshold or the
relative error exceeds 0.5 (``RE_MAX`` of :mod:`inference.evidence.bridge`, for the
same reason) or is not finite. Here, unlike in the bridge, the raw weights are the very
summands of the estimate, which is the case k-hat was made for: above the threshold the
mean of N such weights has no useful accuracy, whatever the delta-method error says.
k-hat is itself estimated from the largest weights drawn, so a proposal that misses a
narrow region of high q entirely (a funnel's neck) can still show a k-hat under the
threshold and a biased estimate.

Blind spot, shared with bridge sampling: posterior draws that all sit in ONE of several
modes fit a proposal around that mode only; the other modes lie far in the proposal's
tail, a finite N essentially never reaches them, and the estimate (with healthy k-hat
and error) is the one mode's share of Z. The estimator is only as good as the draws it
is built from. Draws that span several modes, even in the wrong proportions (chains
stuck in different modes), give a broad proposal that covers them all: the estimate
stays unbiased at a lower efficiency, which is why it can decide where the bridge's
draws sit in several modes; the cost of that breadth grows quickly with the dimension.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from numpyro.infer.util import potential_energy
from scipy import stats
from scipy.special import logsumexp

from beadrod.inference.evidence.bridge import (
    RE_MAX,
    pareto_k_hat,
    pareto_k_threshold,
    posterior_draws,
)
from beadrod.inference.evidence.log_z import EvidenceResult
from beadrod.inference.model.unconstrained import flatten_unconstrained

__all__ = ["importance_sampling_log_z"]


def _program(model: Callable, model_kwargs: dict, num_draws: int, df: float) -> Callable:
    """The compiled part: the draws mapped to the unconstrained space, their mean and the
    Cholesky factor of their covariance, ``num_draws`` Student-t draws and log q there
    (one trace of the model, as in bridge sampling)."""

    def log_q(x, unravel):
        return -potential_energy(model, (), model_kwargs, unravel(x))

    @jax.jit
    def program(flat_draws, key):
        flat, unravel = flatten_unconstrained(model, model_kwargs, flat_draws)
        dim = flat.shape[1]
        mean = flat.mean(axis=0)
        chol = jnp.linalg.cholesky(jnp.atleast_2d(jnp.cov(flat, rowvar=False))
                                   + 1e-12 * jnp.eye(dim))
        kz, kc = jax.random.split(key)
        # multivariate t: m + L z / sqrt(chi2_df / df), one chi-square per draw
        z = jax.random.normal(kz, (num_draws, dim))
        chi2 = 2.0 * jax.random.gamma(kc, 0.5 * df, (num_draws,))
        prop = mean + (z @ chol.T) / jnp.sqrt(chi2 / df)[:, None]
        return mean, chol, prop, jax.vmap(lambda x: log_q(x, unravel))(prop)

    return program


def importance_sampling_log_z(
    model: Callable,
    model_kwargs: dict | None,
    posterior: Mapping[str, Any],
    *,
    num_draws: int = 4000,
    df: float = 5.0,
    seed: int = 0,
    log_density: Any = None,
) -> EvidenceResult:
    """log Z of ``model(**model_kwargs)`` by importance sampling from a Student-t fitted
    to its posterior draws (module docstring).

    ``posterior``: as for :func:`inference.evidence.bridge.bridge_sampling_log_z` (a
    mapping of every latent site to constrained draws shaped (chains, draws, ...), or an
    InferenceData). ``num_draws``: proposal draws N, each one model evaluation.
    ``log_density``: accepted for the same call as the bridge, and not needed: the
    estimate uses log q at the proposal draws only.
    """
    del log_density  # the estimator evaluates the model at its own draws only
    model_kwargs = model_kwargs or {}
    if df <= 2:
        raise ValueError(f"df must exceed 2 (a finite proposal covariance), got {df}")
    if num_draws < 100:
        raise ValueError(f"importance sampling needs >= 100 proposal draws, got {num_draws}")
    t0 = time.perf_counter()
    draws, _ = posterior_draws(model, model_kwargs, posterior, None)
    chains, n_draws = next(iter(draws.values())).shape[:2]
    flat_draws = {k: jnp.asarray(v.reshape(chains * n_draws, *v.shape[2:]))
                  for k, v in draws.items()}
    program = _program(model, model_kwargs, int(num_draws), float(df))
    mean, chol, prop, lq = (np.asarray(a) for a in
                            program(flat_draws, jax.random.PRNGKey(seed)))
    # log g by scipy's multivariate t (an independent implementation of the density the
    # draws above come from)
    log_g = stats.multivariate_t(loc=mean, shape=chol @ chol.T, df=df).logpdf(
        prop.reshape(num_draws, -1))
    log_w = np.asarray(lq, dtype=float) - np.atleast_1d(log_g)
    log_w = np.where(np.isfinite(log_w), log_w, -np.inf)  # outside the support: w = 0
    if not np.any(np.isfinite(log_w)):
        raise RuntimeError("importance sampling: every proposal draw has zero weight")
    n = log_w.size
    log_z = float(logsumexp(log_w) - np.log(n))
    w = np.exp(log_w - np.max(log_w))  # scaled weights: the ratios below are scale-free
    rel = float(np.std(w, ddof=1) / (np.sqrt(n) * np.mean(w)))
    ess = float(np.sum(w) ** 2 / np.sum(w * w))
    k = pareto_k_hat(log_w)
    k_max = pareto_k_threshold(n)
    reasons = []
    if k > k_max:
        reasons.append(f"Pareto k-hat of the weights {k:.2f} > {k_max:.2f}")
    if not np.isfinite(rel):
        reasons.append("relative error not finite")
    elif rel > RE_MAX:
        reasons.append(f"relative error {rel:.2f} > {RE_MAX}")
    wall = time.perf_counter() - t0
    return EvidenceResult("importance_sampling", log_z, rel, wall,
                          settings={"num_draws": n, "df": float(df), "seed": seed,
                                    "dim": int(mean.size), "ess": ess,
                                    "zero_weights": int(np.sum(~np.isfinite(log_w))),
                                    "pareto_k": k, "pareto_k_threshold": k_max,
                                    "reliable": not reasons, "reason": "; ".join(reasons)})
