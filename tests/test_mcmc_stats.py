"""The vectorised R-hat and ESS (inference.sampling.mcmc_stats) against arviz's own, element by
element, on chains with known structure: AR(1) of several correlations, a stuck chain, a
constant element, odd draw counts, heavy tails."""

import arviz as az
import numpy as np
import pytest

from beadrod.inference.sampling import mcmc_stats


def _ar1(rng, chains, draws, k, phi):
    x = np.zeros((chains, draws, k))
    e = rng.standard_normal((chains, draws, k))
    for t in range(1, draws):
        x[:, t] = phi * x[:, t - 1] + e[:, t]
    return x


def _arviz(fn, draws, **kw):
    out = np.empty(draws.shape[2:])
    for j in np.ndindex(*draws.shape[2:]):
        out[j] = float(fn(draws[(slice(None), slice(None), *j)], **kw))
    return out


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # arviz: 0/0 on the constant element
@pytest.mark.parametrize("chains,draws,phi", [(4, 200, 0.0), (4, 201, 0.6), (2, 100, 0.95),
                                              (3, 57, -0.4), (1, 300, 0.3)])
def test_against_arviz(chains, draws, phi):
    rng = np.random.default_rng(chains * 1000 + draws)
    x = _ar1(rng, chains, draws, 6, phi)
    x[..., 1] = np.exp(2.0 * x[..., 1])           # skewed, heavy tail
    x[0, :, 2] += 3.0                               # one chain elsewhere
    x[..., 3] = 1.25                                # constant element
    x = x.reshape(chains, draws, 2, 3)
    np.testing.assert_allclose(mcmc_stats.ess_bulk(x),
                               _arviz(az.ess, x, method="bulk"), rtol=1e-10)
    np.testing.assert_allclose(mcmc_stats.ess_tail(x),
                               _arviz(az.ess, x, method="tail"), rtol=1e-10)
    if chains >= 2:
        ours = mcmc_stats.rhat_rank(x)
        ref = _arviz(az.rhat, x)
        finite = np.isfinite(ref)
        np.testing.assert_allclose(ours[finite], ref[finite], rtol=1e-10)
        assert ours[0, 2] > 1.1  # the stray chain is caught


def test_non_finite_draws_give_nan():
    x = _ar1(np.random.default_rng(0), 4, 100, 2, 0.2)
    x[1, 5, 0] = np.nan
    assert np.isnan(mcmc_stats.rhat_rank(x)[0]) and np.isfinite(mcmc_stats.rhat_rank(x)[1])
    assert np.isnan(mcmc_stats.ess_bulk(x)[0]) and np.isnan(mcmc_stats.ess_tail(x)[0])


def test_gate_stats_is_the_three_statistics():
    x = _ar1(np.random.default_rng(5), 4, 150, 5, 0.5)
    r, eb, et = mcmc_stats.gate_stats(x)
    np.testing.assert_array_equal(r, mcmc_stats.rhat_rank(x))
    np.testing.assert_array_equal(eb, mcmc_stats.ess_bulk(x))
    np.testing.assert_array_equal(et, mcmc_stats.ess_tail(x))
