"""Reliability of the evidence estimators from posterior draws: bridge sampling's
reliability check and the importance-sampling estimator, against closed forms.

Toys: the linear-Gaussian model of tests/test_evidence.py (analytic log Z); the
one-parameter scale model there (log Z by quadrature; its posterior in log tau is skewed);
and a bimodal model y ~ Normal(X (|a|, b), sigma), whose posterior is the linear model's
posterior folded onto a > 0 and mirrored to a < 0: two modes 20 posterior sd apart, and
log Z = log Z_linear + log 2 + log Phi(mu_a / sd_a) exactly. Its draws are drawn exactly
(a Gaussian restricted to a > 0 by rejection, then a sign per draw or per chain), which
makes the cases deterministic and spares NUTS: chains stuck in different modes, chains
that mix between them, and chains that all sit in one.
"""

import jax
import jax.numpy as jnp
import numpy as np
import numpyro
import numpyro.distributions as dist
import pytest
from scipy import integrate, stats

from beadrod.inference.evidence import bridge
from beadrod.inference.evidence.bridge import (
    bridge_sampling_log_z,
    chain_separation,
    pareto_k_hat,
    pareto_k_threshold,
)
from beadrod.inference.evidence.importance import importance_sampling_log_z
from beadrod.inference.evidence.log_z import linear_gaussian_log_evidence
from tests.test_evidence import (  # the toys there, with the same data
    NOISE_SD,
    PRIOR_SD,
    Y_SCALE,
    X,
    Y,
    linear_model,
    scale_model,
)

_RB = np.random.default_rng(3)
XB = _RB.normal(size=(20, 2))
SIG_B, PRIOR_B = 0.5, 2.0
YB = XB @ np.array([1.0, -0.5]) + SIG_B * _RB.normal(size=20)
# the linear model's Gaussian posterior; the bimodal one folds it at a = 0
COV_B = np.linalg.inv(XB.T @ XB / SIG_B**2 + np.eye(2) / PRIOR_B**2)
MU_B = COV_B @ XB.T @ YB / SIG_B**2


def bimodal_model(y=None):
    th = numpyro.sample("theta", dist.Normal(0.0, PRIOR_B).expand([2]).to_event(1))
    eff = jnp.stack([jnp.abs(th[0]), th[1]])
    numpyro.sample("y", dist.Normal(jnp.asarray(XB) @ eff, SIG_B).to_event(1), obs=y)


def bimodal_log_z() -> float:
    # Z = 2 * integral over a > 0 of the linear model's integrand = 2 Z_lin P_lin(a > 0)
    return (linear_gaussian_log_evidence(YB, XB, PRIOR_B, SIG_B) + np.log(2.0)
            + stats.norm.logcdf(MU_B[0] / np.sqrt(COV_B[0, 0])))


def one_mode_draws(rng: np.random.Generator, n: int) -> np.ndarray:
    """n exact draws of the a > 0 mode (rejection; P(a < 0) is 1e-22 here)."""
    out = np.empty((0, 2))
    while len(out) < n:
        d = rng.multivariate_normal(MU_B, COV_B, size=n)
        out = np.concatenate([out, d[d[:, 0] > 0]])
    return out[:n]


CHAINS, DRAWS = 4, 400
KW_B = {"y": jnp.asarray(YB)}


def bimodal_case(kind: str, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    d = np.stack([one_mode_draws(rng, DRAWS) for _ in range(CHAINS)])
    if kind.startswith("stuck"):  # as NUTS chains started in different basins
        d[{"stuck 3/1": 3, "stuck 2/2": 2}[kind]:, :, 0] *= -1
    elif kind == "mixing":  # every draw in either mode with probability 1/2
        d[..., 0] *= np.where(rng.random((CHAINS, DRAWS)) < 0.5, 1.0, -1.0)
    elif kind != "one mode":
        raise ValueError(kind)
    return {"theta": d}


def _nuts_draws(model, kwargs, seed=0, chains=4, draws=400):
    from numpyro.infer import MCMC, NUTS

    mcmc = MCMC(NUTS(model), num_warmup=300, num_samples=draws, num_chains=chains,
                chain_method="vectorized", progress_bar=False)
    mcmc.run(jax.random.PRNGKey(seed), **kwargs)
    return mcmc.get_samples(group_by_chain=True)


KEYS = {"pareto_k_proposal", "pareto_k_posterior",
        "pareto_k_threshold_proposal", "pareto_k_threshold_posterior", "chain_separation",
        "reliable", "reason"}


# --- the building blocks ------------------------------------------------------------


@pytest.mark.parametrize("k", [0.2, 0.5, 0.9])
def test_pareto_k_hat_recovers_a_known_tail(k):
    """Weights U^-k (U uniform) have a Pareto tail of shape k exactly (k-hat's sd is
    about (1 + k)/sqrt(600) from the 600 largest of 40000)."""
    u = np.random.default_rng(1).random(40_000)
    assert abs(pareto_k_hat(-k * np.log(u)) - k) < 0.15
    assert pareto_k_hat(np.zeros(50)) == -np.inf            # equal weights: no tail
    assert pareto_k_hat(np.full(50, -np.inf)) == np.inf      # no weight at all
    with pytest.raises(ValueError):
        pareto_k_hat(np.array([0.0, np.nan]))


def test_pareto_k_threshold():
    assert pareto_k_threshold(100) == pytest.approx(0.5)
    assert pareto_k_threshold(1000) == pytest.approx(2 / 3)
    assert pareto_k_threshold(10**6) == 0.7


def test_chain_separation_sees_displaced_chains_not_noise():
    rng = np.random.default_rng(2)
    flat = rng.normal(size=(4, 500, 5)) * np.array([1.0, 10.0, 0.1, 1.0, 1.0])
    assert chain_separation(flat) < 0.6         # one mode: Monte Carlo noise only
    flat[2:, :, 2] += 0.5                       # 5 within-chain sd along one axis
    assert chain_separation(flat) == pytest.approx(5.0, abs=0.6)
    one = rng.normal(size=(1, 400, 2))
    one[0, 200:, 0] += 4.0                      # one chain that changed mode half-way
    assert chain_separation(one) == pytest.approx(4.0, abs=0.5)
    assert np.isnan(chain_separation(rng.normal(size=(2, 3, 2))))


def test_reliability_rule_fires_on_each_criterion():
    rng = np.random.default_rng(4)
    l1, l2 = rng.normal(size=800), rng.normal(size=800)
    flat = rng.normal(size=(4, 400, 2))
    ok = bridge._reliability(l1, l2, 0.05, 800.0, flat)
    assert KEYS <= ok.keys() and ok["reliable"] and ok["reason"] == ""
    big = bridge._reliability(l1, l2, 0.8, 800.0, flat)
    assert not big["reliable"] and "relative error 0.80" in big["reason"]
    assert "not finite" in bridge._reliability(l1, l2, np.nan, 800.0, flat)["reason"]
    moved = flat.copy()
    moved[0] += 5.0
    apart = bridge._reliability(l1, l2, 0.05, 800.0, moved)
    assert not apart["reliable"] and "chain" in apart["reason"]
    # heavy raw weights are recorded, not a criterion (module docstring of bridge)
    heavy = bridge._reliability(l1, -2.0 * np.log(rng.random(800)), 0.05, 800.0, flat)
    assert heavy["pareto_k_proposal"] > heavy["pareto_k_threshold_proposal"]
    assert heavy["reliable"]


# --- the estimators on the toys -----------------------------------------------------


def test_linear_toy_bridge_reliable_and_importance_sampling_matches():
    ref = linear_gaussian_log_evidence(Y, X, PRIOR_SD, NOISE_SD)
    kw = {"y": jnp.asarray(Y)}
    draws = _nuts_draws(linear_model, kw)
    br = bridge_sampling_log_z(linear_model, kw, draws, seed=3)
    assert KEYS <= br.settings.keys()
    assert br.settings["reliable"] and br.settings["reason"] == "", br.settings
    assert abs(br.log_z - ref) < 3 * br.log_z_err + 0.02, (br, ref)
    imp = importance_sampling_log_z(linear_model, kw, draws, seed=3)
    assert imp.method == "importance_sampling" and imp.settings["reliable"], imp.settings
    assert 0 < imp.log_z_err < 0.05
    assert abs(imp.log_z - ref) < 3 * imp.log_z_err and abs(imp.log_z - ref) < 0.05, (imp, ref)


def test_importance_sampling_keeps_the_jacobian_of_constrained_sites():
    """A prior-only model has Z = 1; a positive site is sampled in log space, and a lost
    Jacobian (or a proposal density that is not the one drawn from) would bias log Z."""

    def prior_only():
        numpyro.sample("theta", dist.Normal(1.0, 2.0).expand([2]).to_event(1))
        numpyro.sample("s", dist.HalfNormal(1.0))

    rng = np.random.default_rng(5)
    post = {"theta": 1.0 + 2.0 * rng.normal(size=(2, 500, 2)),
            "s": np.abs(rng.normal(size=(2, 500)))}
    r = importance_sampling_log_z(prior_only, None, post, num_draws=4000, seed=1)
    assert r.settings["reliable"], r.settings
    assert abs(r.log_z) < 3 * r.log_z_err + 0.01, r
    with pytest.raises(ValueError, match="df"):
        importance_sampling_log_z(prior_only, None, post, df=2.0)


def test_raw_weight_khat_is_no_criterion_for_the_bridge():
    """The scale model's posterior in u = log tau is skewed (doubly exponential on the
    left, the prior's Gaussian on the right): the Normal proposal is a poor importance
    sampler (a raw k-hat above its threshold, on every seed tried), yet the bridge,
    which caps both weights, is exact to its error, and its reliability check passes."""

    def integrand(t):
        return stats.lognorm(1.0).pdf(t) * np.exp(stats.norm(0, t).logpdf(Y_SCALE).sum())

    ref = np.log(integrate.quad(integrand, 0, np.inf, limit=200)[0])
    # exact posterior draws of u = log tau by the inverse CDF on a fine grid
    u = np.linspace(-3.0, 3.0, 60_001)
    log_p = stats.norm.logpdf(u) + stats.norm(0, np.exp(u)[:, None]).logpdf(Y_SCALE).sum(1)
    cdf = integrate.cumulative_trapezoid(np.exp(log_p - log_p.max()), u, initial=0.0)
    tau = np.exp(np.interp(np.random.default_rng(0).random((4, 500)), cdf / cdf[-1], u))
    kw = {"y": jnp.asarray(Y_SCALE)}
    r = bridge_sampling_log_z(scale_model, kw, {"tau": tau}, seed=0)
    s = r.settings
    assert (s["pareto_k_proposal"] > s["pareto_k_threshold_proposal"]
            or s["pareto_k_posterior"] > s["pareto_k_threshold_posterior"]), s
    assert s["reliable"], s
    assert abs(r.log_z - ref) < 3 * r.log_z_err + 0.01, (r, ref)


@pytest.mark.parametrize("kind", ["stuck 3/1", "stuck 2/2"])
def test_bimodal_stuck_chains_flagged_and_importance_sampling_decides(kind):
    """Chains that sit in different modes (NUTS chains started in different basins): the
    pooled draws weight the modes by chain counts (3:1 is wrong, 2:2 right by luck), and
    the bridge flags both by the chains' separation. The t proposal of importance
    sampling, fitted to the same draws, spans both modes, and its estimate is right
    within its error."""
    ref = bimodal_log_z()
    draws = bimodal_case(kind)
    br = bridge_sampling_log_z(bimodal_model, KW_B, draws, seed=1)
    s = br.settings
    assert not s["reliable"] and "chain" in s["reason"], s
    assert s["chain_separation"] > 10 * bridge.SEPARATION_MAX, s
    imp = importance_sampling_log_z(bimodal_model, KW_B, draws, seed=1)
    assert imp.settings["reliable"], imp.settings
    assert abs(imp.log_z - ref) < 3 * imp.log_z_err + 0.05, (imp, ref)


def test_bimodal_mixing_draws_bridge_is_fine():
    """Draws that visit both modes in proportion: the bridge's wide Normal keeps it
    unbiased and its error covers the gap (over seeds the spread is below the reported
    error): nothing to flag, and nothing is flagged."""
    ref = bimodal_log_z()
    br = bridge_sampling_log_z(bimodal_model, KW_B, bimodal_case("mixing"), seed=1)
    assert br.settings["reliable"], br.settings
    assert br.settings["chain_separation"] < 1.0
    assert abs(br.log_z - ref) < 3 * br.log_z_err, (br, ref)


def test_one_mode_of_two_is_invisible():
    """All chains in the a > 0 mode: a fine unimodal sample. Both estimators report the
    one mode's half of Z (log Z - log 2) with small errors, and neither check fires: the
    failure that only draws or a search reaching the other mode can reveal."""
    ref = bimodal_log_z()
    draws = bimodal_case("one mode")
    br = bridge_sampling_log_z(bimodal_model, KW_B, draws, seed=1)
    imp = importance_sampling_log_z(bimodal_model, KW_B, draws, seed=1)
    for r in (br, imp):
        assert r.settings["reliable"], r.settings
        assert abs(r.log_z - (ref - np.log(2.0))) < 3 * r.log_z_err + 0.02, (r, ref)
        assert ref - r.log_z > 0.6  # the missing mode's mass, far outside the error bar


def test_bridge_equation_root_found_where_the_fixed_point_creeps():
    # proposal and posterior barely overlapping: the fixed point crawls; the bracketed
    # root of the same equation is the fully iterated one
    from beadrod.inference.evidence.bridge import _iterate

    rng = np.random.default_rng(2)
    l1 = rng.normal(3.0, 4.0, 60)
    l2 = rng.normal(-9.0, 6.0, 60)
    full, iters = _iterate(l1, l2, max_iter=200_000)
    assert iters > 5
    bracketed, _ = _iterate(l1, l2, max_iter=3)
    assert bracketed == pytest.approx(full, abs=1e-8)
