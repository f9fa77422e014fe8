"""models/ladder/first_order.py: first-order shift against mpmath/scipy references and the paper's claims."""

import jax
import jax.numpy as jnp
import mpmath as mp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate

from beadrod.models.ladder.first_order import (
    complete_elliptic,
    first_order_from_stiffness,
    first_order_hertz,
    first_order_powerlaw,
    max_shift_powerlaw,
    without_first_order,
)
from beadrod.models.ladder.hypergeometric import NEG_INF_GRAD

mp.mp.dps = 30

_powerlaw = jax.jit(first_order_powerlaw)
_hertz = jax.jit(first_order_hertz)
_max_shift = jax.jit(max_shift_powerlaw)
_grad_n = jax.jit(jax.grad(first_order_powerlaw, argnums=1))


def ref_shift_quad(x, n):
    """Eq. (27) by mpmath quadrature of the clipped integrand, split at the kinks."""
    x, n = mp.mpf(x), mp.mpf(n)
    f = lambda t: max(1 + x * mp.sin(t), 0) ** (n - 1)
    if x <= 1:
        mean = mp.quad(f, [-mp.pi / 2, mp.pi / 2, 3 * mp.pi / 2]) / (2 * mp.pi)
    else:
        t0 = mp.asin(-1 / x)
        mean = mp.quad(f, [t0, mp.pi / 2, mp.pi - t0]) / (2 * mp.pi)
    return mean / 2 - mp.mpf(1) / 2


XS = np.array([0.0, 0.2, 0.6, 0.9, 0.99, 1.0 - 1e-9, 1.0, 1.0 + 1e-9, 1.3, 2.0])


def test_hertz_elliptic_matches_hypergeometric_route():
    x = np.concatenate([np.linspace(0.0, 3.0, 301), [1 - 1e-15, 1 - 1e-9, 1 + 1e-9, 50.0]])
    np.testing.assert_allclose(_hertz(x), _powerlaw(x, np.full_like(x, 1.5)), rtol=0, atol=5e-15)


def test_hertz_at_one_paper_value():
    # paper Sec. 5.1 / Fig. 4: about -0.05; exactly sqrt(2)/pi - 1/2
    assert abs(float(_hertz(1.0)) - (np.sqrt(2) / np.pi - 0.5)) < 1e-15
    assert round(float(_hertz(1.0)), 2) == -0.05


@pytest.mark.parametrize("n", [1.0, 1.0 + 1e-9, 1.2, 1.5 - 1e-9, 1.5, 1.5 + 1e-9, 2.0, 2.6, 3.0])
def test_powerlaw_against_mpmath_quadrature(n):
    got = np.asarray(_powerlaw(XS, np.full_like(XS, n)))
    for g, x in zip(got, XS):
        ref = ref_shift_quad(x, n)
        # 1e-13 relative in the mean <...> = 2 (shift + 1/2)
        assert abs(g - float(ref)) < 1e-13 * (abs(float(ref)) + 0.5), (x, n)


def test_powerlaw_against_scipy_quad():
    for x, n in [(0.7, 1.5), (0.999, 1.3), (1.6, 1.5), (0.5, 2.7)]:
        t0, t1 = (np.arcsin(-1 / x), np.pi - np.arcsin(-1 / x)) if x > 1 else (-np.pi / 2, 1.5 * np.pi)
        val, _ = integrate.quad(lambda t, x=x, n=n: max(1 + x * np.sin(t), 0) ** (n - 1), t0, t1,
                                points=[np.pi / 2], epsabs=0, epsrel=1e-13, limit=200)
        assert abs(float(_powerlaw(x, n)) - (val / (4 * np.pi) - 0.5)) < 1e-12


def test_complete_elliptic_against_mpmath():
    for kp2 in [1.0, 0.7, 0.3, 1e-3, 1e-9, 1e-15]:
        k_int, e_int = complete_elliptic(kp2)
        m = 1 - mp.mpf(kp2)
        assert abs(float(k_int) / float(mp.ellipk(m)) - 1) < 1e-14
        assert abs(float(e_int) / float(mp.ellipe(m)) - 1) < 1e-14


def test_max_shift_sign_versus_n_paper_fig5():
    """Negative for 1 < n < 2, zero at n = 1, 2, positive for n > 2 (paper Sec. 5.4)."""
    n = np.array([1.0, 1.01, 1.3, 1.5, 1.9, 1.99, 2.0, 2.01, 2.5, 3.0, 4.0])
    s = np.asarray(_max_shift(n))
    assert abs(s[0]) < 1e-15 and abs(s[6]) < 1e-15
    assert np.all(s[1:6] < 0) and np.all(s[7:] > 0)
    assert abs(s[-2] - 0.25) < 5e-15  # n = 3: <(1 + sin)^2> = 3/2
    np.testing.assert_allclose(s, _powerlaw(np.ones_like(n), n), rtol=0, atol=1e-15)


def test_max_shift_minimum_is_below_hertz_near_n_1p4():
    # independent: stationary point of the Gamma closed form by mpmath
    n_star = mp.findroot(lambda n: mp.digamma(n) - mp.digamma(n - mp.mpf(1) / 2) - mp.log(2), 1.45)
    v_star = 2 ** (n_star - 2) * mp.gamma(n_star - mp.mpf(1) / 2) / (mp.sqrt(mp.pi) * mp.gamma(n_star)) - 0.5
    assert abs(float(n_star) - 1.4004) < 1e-3 and abs(float(v_star) + 0.05169) < 1e-5
    grid = np.linspace(1.0, 3.0, 2001)
    s = np.asarray(_max_shift(grid))
    assert abs(grid[np.argmin(s)] - float(n_star)) < 1.5e-3
    assert abs(s.min() - float(v_star)) < 1e-7   # grid step 1e-3 at a quadratic minimum
    assert s.min() < float(_max_shift(1.5)) < -0.049  # Hertz is close to, not at, the minimum


def test_first_order_from_stiffness_reproduces_powerlaw():
    for n in [1.5, 2.3]:
        k = lambda d, n=n: n * 3.0 * d ** (n - 1.0)   # C = 3, delta0 = 2e-8 m
        x = np.array([0.0, 0.5, 0.99, 0.999999, 1.0, 1.0001, 1.5, 4.0])
        got = first_order_from_stiffness(k, 2e-8, x)
        ref = _powerlaw(x, np.full_like(x, n))
        tol = np.where(np.abs(x - 1.0) < 1e-3, 1e-9, 1e-12)
        assert np.all(np.abs(np.asarray(got) - np.asarray(ref)) < tol)


def test_first_order_from_stiffness_clips_and_broadcasts():
    # the stiffness is never evaluated where delta <= 0 (it would be NaN here)
    k = lambda d: jnp.sqrt(d) * 1.5
    d0 = jnp.array([1e-8, 2e-8])
    scale = jnp.array([1.0, 3.0])          # a closure over a batched parameter
    kb = lambda d: scale * jnp.sqrt(d)
    a = first_order_from_stiffness(k, d0, jnp.array([1.7, 2.5]))
    b = first_order_from_stiffness(kb, d0, jnp.array([1.7, 2.5]))
    assert np.all(np.isfinite(a))
    np.testing.assert_allclose(a, b, rtol=1e-14)
    np.testing.assert_allclose(a, _powerlaw(np.array([1.7, 2.5]), np.full(2, 1.5)), atol=1e-12)
    g = jax.grad(lambda xx: first_order_from_stiffness(k, 1e-8, xx))(1.7)
    assert np.isfinite(g)


def test_without_first_order():
    # Fig. 4 grey curve: sqrt(<K>/K0) - 1 with <K>/K0 = 2 (shift + 1/2)
    ratio = 2 * (np.asarray(_hertz(1.0)) + 0.5)
    assert abs(float(without_first_order(ratio)) - (np.sqrt(2 * np.sqrt(2) / np.pi) - 1)) < 1e-15
    assert float(without_first_order(1.0)) == 0.0


def test_gradients_finite_over_sampler_region():
    """Sampler region: n in [1, 3], x in [0, 1.5]; x = 1, n = 1, 3/2, 2 exactly included."""
    xs, ns = np.meshgrid(np.linspace(0.0, 1.5, 31), np.array([1.0, 1.0 + 1e-9, 1.25, 1.5, 1.75,
                                                              2.0, 2.5, 3.0]))
    vg = jax.jit(jax.vmap(jax.value_and_grad(first_order_powerlaw, argnums=(0, 1))))
    v, (gx, gn) = vg(jnp.asarray(xs.ravel()), jnp.asarray(ns.ravel()))
    assert np.all(np.isfinite(v)) and np.all(np.isfinite(gx)) and np.all(np.isfinite(gn))
    gh = jax.jit(jax.vmap(jax.grad(first_order_hertz)))(jnp.linspace(0.0, 1.5, 31))
    assert np.all(np.isfinite(gh))
    assert float(jax.grad(first_order_hertz)(1.0)) == 0.5 * NEG_INF_GRAD


def test_gradient_in_n_against_mpmath():
    for x, n in [(0.5, 1.5), (1.0, 1.5), (1.0, 1.2), (1.4, 2.5), (2.5, 1.8)]:
        g = float(_grad_n(x, n))
        ref = mp.diff(lambda nn, x=x: ref_shift_quad(x, nn), n)
        assert abs(g - float(ref)) < 1e-10


@settings(max_examples=40, deadline=None)
@given(st.floats(0.0, 1.0), st.floats(1.01, 1.99))
def test_shift_negative_and_falling_for_1_lt_n_lt_2(x, n):
    a, b = _powerlaw(np.array([x, min(x + 0.05, 1.0)]), np.full(2, n))
    assert float(a) <= 1e-16 and float(b) <= float(a) + 1e-15
