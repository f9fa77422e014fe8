"""The tabulated JKR first-order shift (models/laws/jkr/table.py) against the quadrature it
replaces, its E*-invariance (the reason a (x, F0/Fc) table is exact in structure), its
Hertz limit (independent closed form) and finite gradients where NUTS goes."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from beadrod.models.ladder.first_order import first_order_hertz
from beadrod.models.laws import jkr
from beadrod.models.laws.jkr import table

R = 0.007938


def _quadrature(x, ratio, e_star=2e11, load=0.02):
    gamma = load / (3 * np.pi * ratio * R)
    return np.asarray(jkr.contact.shift_first_order(jnp.asarray(x), load=load, e_star=e_star,
                                            radius=R, gamma=gamma))


@pytest.mark.parametrize("ratio", [0.01, 0.3, 3.0, 100.0])
def test_curve_does_not_depend_on_modulus(ratio):
    x = np.linspace(0.05, 1.9, 17)
    a = _quadrature(x, ratio, e_star=1.0e11)
    b = _quadrature(x, ratio, e_star=2.6e11)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-14)


def test_table_matches_quadrature_at_random_points():
    rng = np.random.default_rng(7)
    x = np.concatenate([rng.uniform(0, 2, 300), 1 + rng.uniform(-1e-3, 1e-3, 40)])
    r = np.exp(rng.uniform(np.log(2e-3), np.log(5e5), x.size))
    ref = _quadrature(x, r)
    fast = np.asarray(table.shift_first_order_fast(x, r))
    # measured 1.8e-7 worst (next to x = 1 at large r), ~3e-8 elsewhere
    assert np.max(np.abs(fast - ref)) < 5e-7
    assert np.max(np.abs(fast - ref)[np.abs(x - 1) > 0.01]) < 1e-7


def test_hertz_limit_against_closed_form():
    x = np.linspace(0.0, 0.99, 12)
    fast = np.asarray(table.shift_first_order_fast(x, table.R_MAX))
    np.testing.assert_allclose(fast, np.asarray(first_order_hertz(jnp.asarray(x))), atol=2e-5)


def test_load_ratio_matches_pull_off_force():
    gamma = 0.7
    fc = float(jkr.contact.pull_off_force(gamma=gamma, radius=R))
    assert float(table.load_ratio(0.02, gamma=gamma, radius=R)) == pytest.approx(0.02 / fc)


def test_gradients_finite_everywhere_nuts_goes():
    x = jnp.concatenate([jnp.linspace(0.0, 2.0, 41), jnp.array([1 - 1e-12, 1.0, 1 + 1e-12, 2.5])])
    gamma = jnp.array([1e-3, 0.1, 0.7, 5.0, 1e3])

    def s(xx, g):
        return table.shift_first_order_fast(xx, table.load_ratio(0.02, gamma=g,
                                                                          radius=R))

    gx, gg = jax.jit(jax.vmap(jax.vmap(jax.grad(s, argnums=(0, 1)), (0, None)), (None, 0)))(x, gamma)
    assert np.all(np.isfinite(gx)) and np.all(np.isfinite(gg))
    # d/d gamma against a central difference at an interior point
    h = 1e-6
    fd = (s(0.7, 0.7 + h) - s(0.7, 0.7 - h)) / (2 * h)
    assert float(jax.grad(s, argnums=1)(0.7, 0.7)) == pytest.approx(float(fd), rel=1e-5)
