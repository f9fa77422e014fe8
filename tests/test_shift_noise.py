"""The shifts' protocol noise model against dense linear algebra: the joint density of
a protocol's sweeps (covariance D + tau^2 1 1^T) against scipy's multivariate normal,
the leave-one-out conditionals against Gaussian conditioning, the joint draws against
the covariance, and the limits (tau = 0, one sweep per protocol)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

from beadrod.inference.model.shift_noise import (
    ProtocolNormal,
    joint_log_density,
    loo_conditional,
    noise_variance,
)

RNG = np.random.default_rng(3)
PROTO = np.array([0, 0, 0, 1, 1, 2, 2, 2, 2, 3])
P = 4


def _cov(var, tau, proto):
    return np.diag(var) + tau**2 * (proto[:, None] == proto[None, :])


@pytest.fixture
def case():
    pred = -np.abs(RNG.normal(0.02, 0.02, PROTO.size))
    var = np.asarray(noise_variance(pred, sigma=1e-3, kappa=0.15))
    y = RNG.multivariate_normal(pred, _cov(var, 2e-3, PROTO))
    return y, pred, var


@pytest.mark.parametrize("tau", [0.0, 1e-4, 2e-3, 0.05])
def test_joint_density_is_the_multivariate_normal(case, tau):
    y, pred, var = case
    got = float(jnp.sum(joint_log_density(jnp.asarray(y - pred), jnp.asarray(var), tau,
                                          jnp.asarray(PROTO), P)))
    want = stats.multivariate_normal(pred, _cov(var, tau, PROTO)).logpdf(y)
    assert got == pytest.approx(want, rel=1e-12, abs=1e-9)


@pytest.mark.parametrize("tau", [0.0, 2e-3, 0.05])
def test_loo_conditional_is_gaussian_conditioning(case, tau):
    y, pred, var = case
    m, v = loo_conditional(jnp.asarray(y - pred), jnp.asarray(var), tau, jnp.asarray(PROTO), P)
    cov = _cov(var, tau, PROTO)
    r = y - pred
    for i in range(y.size):
        rest = np.arange(y.size) != i
        gain = np.linalg.solve(cov[np.ix_(rest, rest)], cov[rest, i])
        assert float(m[i]) == pytest.approx(gain @ r[rest], rel=1e-9, abs=1e-15)
        assert float(v[i]) == pytest.approx(cov[i, i] - cov[i, rest] @ gain, rel=1e-9)
    # a protocol of one sweep has nothing to condition on
    assert float(m[-1]) == 0.0 and float(v[-1]) == pytest.approx(var[-1] + tau**2)


def test_pointwise_log_prob_is_the_conditional_and_default_the_joint(case):
    y, pred, var = case
    d = ProtocolNormal(jnp.asarray(pred), jnp.asarray(var), 2e-3, jnp.asarray(PROTO), P)
    assert float(jnp.sum(d.log_prob(jnp.asarray(y)))) == pytest.approx(
        stats.multivariate_normal(pred, _cov(var, 2e-3, PROTO)).logpdf(y), rel=1e-12)
    pw = ProtocolNormal(jnp.asarray(pred), jnp.asarray(var), 2e-3, jnp.asarray(PROTO), P,
                       pointwise=True)
    m, v = loo_conditional(jnp.asarray(y - pred), jnp.asarray(var), 2e-3,
                           jnp.asarray(PROTO), P)
    want = stats.norm(pred + np.asarray(m), np.sqrt(np.asarray(v))).logpdf(y)
    np.testing.assert_allclose(np.asarray(pw.log_prob(jnp.asarray(y))), want, rtol=1e-12)


def test_joint_draws_have_the_covariance(case):
    _, pred, var = case
    tau = 5e-3
    d = ProtocolNormal(jnp.asarray(pred), jnp.asarray(var), tau, jnp.asarray(PROTO), P)
    draws = np.asarray(d.sample(jax.random.PRNGKey(0), (200_000,)))
    assert np.all(np.abs(draws.mean(axis=0) - pred) < 5 * np.sqrt(var + tau**2) / 447)
    emp = np.cov(draws, rowvar=False)
    cov = _cov(var, tau, PROTO)
    # sampling error of a covariance entry: ~ sqrt((c_ii c_jj + c_ij^2)/n)
    err = np.sqrt((np.outer(np.diag(cov), np.diag(cov)) + cov**2) / draws.shape[0])
    assert np.all(np.abs(emp - cov) < 5 * err)


def test_gradients_finite_at_tau_zero(case):
    y, pred, var = case

    def total(tau, kappa):
        v = noise_variance(jnp.asarray(pred), sigma=1e-3, kappa=kappa)
        return jnp.sum(joint_log_density(jnp.asarray(y - pred), v, tau, jnp.asarray(PROTO), P))

    g = jax.grad(total, argnums=(0, 1))(0.0, 0.0)
    assert all(np.isfinite(float(x)) for x in g)
