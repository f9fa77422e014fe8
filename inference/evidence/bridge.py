"""log Z by bridge sampling from the NUTS draws (Meng & Wong 1996; Gronau et al. 2017).

The cheap second estimator next to nested sampling: it reuses the posterior draws the
comparison already has and needs only log-density values (no gradients, no new MCMC).

Method, in the unconstrained space u of the model (numpyro's transforms), where the
unnormalised posterior is q(u) = exp(-potential_energy(u)) = p(y, theta(u)) |J(u)| and
Z = integral q(u) du:

1. Split each chain's draws in halves. The first halves fit the proposal
   g = Normal(mean, cov) (sample moments); the second halves (N1 draws) enter the bridge,
   so proposal and bridge draws are independent (Overstall & Forster 2010).
2. Draw N2 = N1 points from g (in the same compiled program as the transforms). With
   l1 = log q - log g at the N1 posterior draws and l2 the same at the N2 proposal
   draws, s1 = N1/(N1+N2), s2 = N2/(N1+N2), iterate the optimal bridge (Meng & Wong
   1996, Eq. 4.1), in log space::

       r <- [ (1/N2) sum_j e^l2_j / (s1 e^l2_j + s2 r) ] / [ (1/N1) sum_i 1/(s1 e^l1_i + s2 r) ]

   to a fixed point; log Z = log r.
3. Error: the approximate relative mean-squared error of Fruehwirth-Schnatter (2004),
   as in the bridgesampling R package (Gronau, Singmann & Wagenmakers 2020)::

       RE^2 = V(f1)/(N2 E(f1)^2) + (N1/ESS(f2)) V(f2)/(N1 E(f2)^2),
       f1 = (e^l2/r)/(s1 e^l2/r + s2) at the proposal draws,
       f2 = 1/(s1 e^l1/r + s2) at the posterior draws,

   the ESS (ArviZ, over the chains) accounting for the autocorrelation of the NUTS
   draws; the log Z error is RE (a relative error of Z). Validated on the
   linear-Gaussian toy with an analytic evidence (tests/test_evidence.py).

log q at the bridge draws is what NUTS recorded as minus the potential energy of each
draw (``sample_stats.lp``) when the caller passes it, so the model is evaluated only at
the proposal draws.

The estimate is only as good as the draws: a run that failed its diagnostics gate gives
an untrustworthy bridge estimate, and the comparison table marks it so. The normal
proposal suits unimodal posteriors (all of beadrod's models); a multimodal posterior
shows as a large RE.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import arviz as az
import jax
import jax.numpy as jnp
import numpy as np
from numpyro.infer.util import potential_energy
from scipy.special import logsumexp

from beadrod.inference.evidence.log_z import EvidenceResult, latent_site_names
from beadrod.inference.model.unconstrained import flatten_unconstrained

__all__ = ["bridge_sampling_log_z"]


def _iterate(l1: np.ndarray, l2: np.ndarray, *, tol: float = 1e-10,
             max_iter: int = 10_000) -> tuple[float, int]:
    # plain NumPy: a few thousand numbers, iterated on the host
    n1, n2 = l1.size, l2.size
    ls1, ls2 = np.log(n1 / (n1 + n2)), np.log(n2 / (n1 + n2))
    log_r = float(np.median(l1))
    for k in range(max_iter):
        num = logsumexp(l2 - np.logaddexp(ls1 + l2, ls2 + log_r)) - np.log(n2)
        den = logsumexp(-np.logaddexp(ls1 + l1, ls2 + log_r)) - np.log(n1)
        new = float(num - den)
        if abs(new - log_r) < tol:
            return new, k + 1
        log_r = new
    raise RuntimeError(f"bridge sampling did not converge in {max_iter} iterations")


def _relative_error(l1: np.ndarray, l2: np.ndarray, log_r: float,
                    chains: int) -> tuple[float, float]:
    n1, n2 = l1.size, l2.size
    s1, s2 = n1 / (n1 + n2), n2 / (n1 + n2)
    e2 = np.exp(np.clip(l2 - log_r, -700, 700))
    f1 = e2 / (s1 * e2 + s2)
    f2 = 1.0 / (s1 * np.exp(np.clip(l1 - log_r, -700, 700)) + s2)
    ess = float(az.ess(f2.reshape(chains, -1)))
    ess = min(max(ess, 1.0), float(n1))
    re2 = (np.var(f1) / (n2 * np.mean(f1) ** 2)
           + (n1 / ess) * np.var(f2) / (n1 * np.mean(f2) ** 2))
    return float(np.sqrt(re2)), ess


def _program(model: Callable, model_kwargs: dict, chains: int, half: int, n2: int,
             known: bool) -> Callable:
    """The compiled part of bridge sampling: the draws mapped to the unconstrained space,
    split into the proposal's and the bridge's halves of each chain, the proposal's mean
    and Cholesky factor from the first halves, ``n2`` proposal draws and log q at them
    (and at the bridge draws unless ``known``)."""

    def log_q(x, unravel):
        return -potential_energy(model, (), model_kwargs, unravel(x))

    @jax.jit
    def program(flat_draws, key):
        flat, unravel = flatten_unconstrained(model, model_kwargs, flat_draws)
        flat = flat.reshape(chains, -1, flat.shape[-1])
        fit = flat[:, :half].reshape(-1, flat.shape[-1])
        bridge = flat[:, half:].reshape(-1, flat.shape[-1])
        dim = fit.shape[1]
        mean = fit.mean(axis=0)
        chol = jnp.linalg.cholesky(jnp.atleast_2d(jnp.cov(fit, rowvar=False))
                                   + 1e-12 * jnp.eye(dim))
        prop = mean + jax.random.normal(key, (n2, dim)) @ chol.T
        lq = jax.vmap(lambda x: log_q(x, unravel))
        return mean, chol, bridge, prop, (None if known else lq(bridge)), lq(prop)

    return program


def bridge_sampling_log_z(
    model: Callable,
    model_kwargs: dict | None,
    posterior: Mapping[str, Any],
    *,
    num_proposal: int | None = None,
    seed: int = 0,
    log_density: Any = None,
) -> EvidenceResult:
    """log Z of ``model(**model_kwargs)`` from its posterior draws by bridge sampling.

    ``posterior`` maps every latent site to its constrained draws shaped (chains, draws,
    ...) (``idata.posterior`` works, or ``mcmc.get_samples(group_by_chain=True)``); or it
    is the whole InferenceData of a NUTS run, whose recorded ``sample_stats.lp`` then
    serves as ``log_density`` unless one is given.
    ``num_proposal`` defaults to the number of bridge draws (half of all draws).
    ``log_density``: log q(u) = -potential_energy at each draw, shaped (chains, draws),
    where the sampler recorded it (NUTS's ``sample_stats.lp``); it spares evaluating the
    model at the bridge draws, half of the work.
    """
    model_kwargs = model_kwargs or {}
    t0 = time.perf_counter()
    if hasattr(posterior, "posterior"):  # an InferenceData
        stats = getattr(posterior, "sample_stats", None)
        if log_density is None and stats is not None and "lp" in stats:
            log_density = stats["lp"]
        posterior = posterior.posterior
    latents = latent_site_names(model, model_kwargs)
    missing = [k for k in latents if k not in posterior]
    if missing:
        raise KeyError(f"posterior draws lack the latent site(s) {missing}")
    draws = {k: np.asarray(posterior[k], dtype=float) for k in latents}
    chains, n_draws = next(iter(draws.values())).shape[:2]
    if n_draws < 20:
        raise ValueError(f"bridge sampling needs >= 20 draws per chain, got {n_draws}")
    half = n_draws // 2
    n1 = chains * (n_draws - half)
    n2 = int(num_proposal or n1)
    flat_draws = {k: jnp.asarray(v.reshape(chains * n_draws, *v.shape[2:]))
                  for k, v in draws.items()}
    known = log_density is not None
    # one compiled program (one trace of the model): eagerly, the model's every operation
    # is dispatched (and its loops compiled) one by one, slow for the adhesive laws
    program = _program(model, model_kwargs, chains, half, n2, known)
    mean, chol, bridge, prop, lq_bridge, lq_prop = (
        None if a is None else np.asarray(a)
        for a in program(flat_draws, jax.random.PRNGKey(seed)))
    dim = mean.size
    log_det = float(np.sum(np.log(np.diag(chol))))

    def log_g(x: np.ndarray) -> np.ndarray:
        w = np.linalg.solve(chol, (x - mean).T)
        return -0.5 * np.sum(w * w, axis=0) - log_det - 0.5 * dim * np.log(2 * np.pi)

    if known:
        lq_bridge = np.asarray(log_density, dtype=float)[:, half:].reshape(-1)
    l1 = np.asarray(lq_bridge) - log_g(bridge)
    l2 = np.asarray(lq_prop) - log_g(prop)
    l2 = np.where(np.isfinite(l2), l2, -np.inf)
    if not np.all(np.isfinite(l1)):
        raise RuntimeError("non-finite log density at a posterior draw: cannot bridge")
    log_z, iters = _iterate(l1, l2)
    re, ess = _relative_error(l1, l2, log_z, chains)
    wall = time.perf_counter() - t0
    return EvidenceResult("bridge_sampling", float(log_z), re, wall,
                          settings={"n_bridge": int(n1), "n_proposal": n2, "seed": seed,
                                    "iterations": iters, "ess_f2": ess, "dim": int(dim)})
