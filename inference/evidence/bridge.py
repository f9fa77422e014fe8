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
proposal suits unimodal posteriors; a law with a loss term can have two modes.

Reliability (``settings['reliable']``, with ``settings['reason']`` saying why not). From
quantities the estimator already has, the estimate is flagged when

* the relative error RE > 0.5 (``RE_MAX``), or RE is not finite: the first-order error
  is meaningful only for RE << 1 (log(1 +- 0.5) is +0.41 / -0.69: the log Z error is
  then neither symmetric nor small), and a 2-sigma band of +-1 nat spans the whole "not
  worth more than a bare mention" grade of a Bayes factor (2 ln B < 2, Kass & Raftery
  1995), so such an estimate cannot rank laws whatever its central value;
* the chains disagree (a mode check that does not rely on tails): each chain is split
  in halves (as split-R-hat does) and ``chain_separation`` is the largest Mahalanobis
  distance between two halves' means in the unconstrained space, in units of the
  pooled within-half covariance W. Above 2 (``SEPARATION_MAX``) the halves sit in
  different places: a mixture of two equal normals with a common sd is bimodal exactly
  when their means are more than 2 sd apart (Schilling, Watkins & Watkins 2002, Am.
  Stat. 56, 223), so two halves that far apart look like two modes (or a chain that
  has not converged), and the pooled draws weight the modes by chain counts, not by
  mass. Halves that sample one mode have means that differ only by Monte Carlo noise,
  D^2 ~ 2 chi2_d / ESS_half for one pair; a false alarm needs chi2_d > 2 ESS_half,
  which does not happen once the per-half ESS is a few times the dimension d.

Recorded, and deliberately not a criterion: the Pareto k-hat (``arviz.psislw``: the
shape of a generalised Pareto distribution fitted to the largest weights, Zhang &
Stephens 2009; Vehtari, Simpson, Gelman, Yao & Gabry 2024, "Pareto smoothed importance
sampling", JMLR 25(72)) of the two raw importance weights the bridge combines:
``pareto_k_proposal`` of e^l2 = q/g at the proposal draws (g misses posterior mass in
its tails; the variational diagnostic of Yao, Vehtari, Simpson & Gelman 2018, "Yes, but
did it work?", ICML) and ``pareto_k_posterior`` of e^-l1 = g/q at the posterior draws
(g puts mass where the posterior has little), each with its sample-size-dependent
threshold min(1 - 1/log10(S), 0.7) (``pareto_k_threshold_*``; for the autocorrelated
posterior draws the tail length uses their relative efficiency ESS(f2)/N1). Micaletto &
Vehtari (2025, "Bridge sampling diagnostics", arXiv:2508.14487) propose Pareto-k-hat
diagnostics for bridge sampling. Why not a criterion here: k-hat judges g as an
importance-sampling proposal, which the bridge does not need it to be, since its
optimal bridge function caps both weights (f1 < 1/s1, f2 <= 1/s2). On the
one-parameter posterior of a log-transformed scale (tests/test_evidence_reliability.py),
skewed in u, one of the two k-hats, and mostly both, exceeds the threshold on every
seed tried while the bridge is exact to its error of 0.005 nat; the k-hat of the
bridge's capped summands f1, f2 does the same (a plateau of weights with a few 4x
larger ones fits a heavy tail though the mean hardly moves); and on draws that mix
between two modes the k-hat of g/q scatters across the threshold from run to run while
the bridge is unbiased with an honest error. So k-hat would flag sound estimates and
would not flag the bimodal failure more surely than the chain check does.

A bimodal posterior whose draws mix between the modes (every chain visits both in the
right proportions) is no failure: the bridge with its wide Normal stays unbiased and its
RE covers the spread. Chains that sit in different modes are one, and the chain check
flags them. What no check here can see: chains that all sample ONE of two modes. Their
draws are a fine unimodal sample, the Normal fits them, RE, k-hat and the chain means
are all healthy, and log Z misses the other mode's mass (log 2 for two mirror modes).
Only draws or a search that reach the other mode reveal it (nested sampling; a
multi-start mode search). A fixed point that is not reached raises RuntimeError (no
estimate), as before.
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

__all__ = [
    "bridge_sampling_log_z",
    "posterior_draws",
    "pareto_k_hat",
    "pareto_k_threshold",
    "chain_separation",
    "RE_MAX",
    "SEPARATION_MAX",
]

RE_MAX = 0.5  # relative error of Z above which the estimate is unreliable (module docstring)
SEPARATION_MAX = 2.0  # chain_separation [within-chain sd] above which the chains disagree


def pareto_k_hat(log_weights: np.ndarray, *, reff: float = 1.0) -> float:
    """Pareto k-hat of the weights e^log_weights: the shape of a generalised Pareto
    distribution fitted to their largest values (``arviz.psislw``: tail length
    min(S/5, 3 sqrt(S/reff)), Zhang & Stephens 2009 fit; Vehtari et al. 2024).

    -inf entries are zero weights and stay in. Weights that are all equal have no tail:
    -inf. Too few positive weights to fit a tail give +inf (arviz's convention).
    """
    lw = np.asarray(log_weights, dtype=float).ravel()
    if np.any(np.isnan(lw)) or np.any(lw == np.inf):
        raise ValueError("NaN or +inf among the log weights")
    finite = lw[np.isfinite(lw)]
    if finite.size == 0:
        return float("inf")
    if finite.size == lw.size and np.ptp(finite) == 0.0:
        return float("-inf")
    _, k = az.psislw(lw, reff=reff, normalize=False)
    return float(k)


def pareto_k_threshold(n: int) -> float:
    """min(1 - 1/log10(n), 0.7): the largest k-hat at which a Monte Carlo (or importance
    sampling) mean of n draws still has a small error with high probability (Vehtari et
    al. 2024); 0.5 at n = 100, 0.67 at n = 1000, 0.7 from n = 2154 on."""
    return float(min(1.0 - 1.0 / np.log10(n), 0.7))


def chain_separation(flat: np.ndarray) -> float:
    """Largest Mahalanobis distance between the means of the split chains of ``flat``
    (chains, draws, dim), in units of their pooled within-half covariance.

    Each chain is cut into a first and a second half, as for split-R-hat, so that one
    chain that moved from one mode to another shows as well as two chains in different
    modes. NaN when a half has fewer than two draws.
    """
    flat = np.asarray(flat, dtype=float)
    c, n, d = flat.shape
    h = n // 2
    if h < 2:
        return float("nan")
    halves = np.concatenate([flat[:, :h], flat[:, n - h:]], axis=0)   # (2c, h, d)
    means = halves.mean(axis=1)
    cent = halves - means[:, None, :]
    w = np.einsum("chi,chj->ij", cent, cent) / (2 * c * (h - 1))
    # a (numerically) constant coordinate: a relative floor keeps W invertible
    w = w + 1e-12 * (np.trace(w) / d + 1e-300) * np.eye(d)
    chol = np.linalg.cholesky(w)
    z = np.linalg.solve(chol, means.T).T                               # whitened means
    diff = z[:, None, :] - z[None, :, :]
    return float(np.sqrt(np.max(np.sum(diff * diff, axis=-1))))


def posterior_draws(model: Callable, model_kwargs: dict, posterior: Mapping[str, Any],
                    log_density: Any) -> tuple[dict[str, np.ndarray], Any]:
    """(draws, log_density): every latent site's constrained draws (chains, draws, ...)
    from a mapping or an InferenceData, whose ``sample_stats.lp`` serves as
    ``log_density`` unless one is given."""
    if hasattr(posterior, "posterior"):  # an InferenceData
        stats = getattr(posterior, "sample_stats", None)
        if log_density is None and stats is not None and "lp" in stats:
            log_density = stats["lp"]
        posterior = posterior.posterior
    latents = latent_site_names(model, model_kwargs)
    missing = [k for k in latents if k not in posterior]
    if missing:
        raise KeyError(f"posterior draws lack the latent site(s) {missing}")
    return {k: np.asarray(posterior[k], dtype=float) for k in latents}, log_density


def _iterate(l1: np.ndarray, l2: np.ndarray, *, tol: float = 1e-10,
             max_iter: int = 1000) -> tuple[float, int]:
    # plain NumPy: a few thousand numbers, iterated on the host
    n1, n2 = l1.size, l2.size
    ls1, ls2 = np.log(n1 / (n1 + n2)), np.log(n2 / (n1 + n2))

    def step(log_r: float) -> float:
        num = logsumexp(l2 - np.logaddexp(ls1 + l2, ls2 + log_r)) - np.log(n2)
        den = logsumexp(-np.logaddexp(ls1 + l1, ls2 + log_r)) - np.log(n1)
        return float(num - den)

    log_r = float(np.median(l1))
    for k in range(max_iter):
        new = step(log_r)
        if abs(new - log_r) < tol:
            return new, k + 1
        log_r = new
    # the fixed point creeps where proposal and posterior barely overlap (few draws in
    # many dimensions); the same equation, r B(r) = A(r), has one root, and
    # step(t) - t = ln A - ln(r B) is strictly decreasing in t = ln r (A falls with r,
    # r B rises): bracket it and bisect
    from scipy.optimize import brentq

    def phi(t: float) -> float:
        return step(t) - t

    lo = hi = float(np.median(l1))
    width = 1.0
    while phi(lo) < 0 and width < 1e4:
        lo -= width
        width *= 2
    width = 1.0
    while phi(hi) > 0 and width < 1e4:
        hi += width
        width *= 2
    if not (phi(lo) >= 0 >= phi(hi)):
        raise RuntimeError("bridge sampling: no root of the bridge equation within "
                           f"1e4 nats of the draws' median log weight ({max_iter} "
                           "fixed-point iterations did not converge)")
    return float(brentq(phi, lo, hi, xtol=tol, rtol=1e-15)), max_iter


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
    (and at the bridge draws unless ``known``), and all draws (chains, draws, dim) for
    the chains' agreement."""

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
        return (mean, chol, bridge, prop, (None if known else lq(bridge)), lq(prop),
                flat)

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
    draws, log_density = posterior_draws(model, model_kwargs, posterior, log_density)
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
    mean, chol, bridge, prop, lq_bridge, lq_prop, flat = (
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
    check = _reliability(l1, l2, re, ess, flat)
    wall = time.perf_counter() - t0
    return EvidenceResult("bridge_sampling", float(log_z), re, wall,
                          settings={"n_bridge": int(n1), "n_proposal": n2, "seed": seed,
                                    "iterations": iters, "ess_f2": ess, "dim": int(dim),
                                    **check})


def _reliability(l1: np.ndarray, l2: np.ndarray, re: float, ess: float,
                 flat: np.ndarray) -> dict[str, Any]:
    """The settings entries of the reliability check (module docstring)."""
    n1, n2 = l1.size, l2.size
    reff = min(max(ess / n1, 1.0 / n1), 1.0)  # posterior draws: autocorrelated
    sep = chain_separation(flat)
    reasons = []
    if not np.isfinite(re):
        reasons.append("relative error not finite")
    elif re > RE_MAX:
        reasons.append(f"relative error {re:.2f} > {RE_MAX}")
    if sep > SEPARATION_MAX:  # NaN (too few draws) does not fire
        reasons.append(f"chain halves' means {sep:.1f} within-chain sd apart "
                       f"(> {SEPARATION_MAX:g}): more than one mode, or unconverged chains")
    return {"pareto_k_proposal": pareto_k_hat(l2),
            "pareto_k_posterior": pareto_k_hat(-l1, reff=reff),
            "pareto_k_threshold_proposal": pareto_k_threshold(n2),
            "pareto_k_threshold_posterior": pareto_k_threshold(n1),
            "chain_separation": sep, "reliable": not reasons, "reason": "; ".join(reasons)}
