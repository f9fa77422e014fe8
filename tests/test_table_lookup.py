"""The table lookups' fast evaluation: the Chebyshev basis from powers, the closed-form
knot location, and the derivatives written by hand (models.scalar_shape, models.p_cells),
each against an independent reference (numpy's Clenshaw sums, finite differences)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from numpy.polynomial import chebyshev as npcheb

from models import backbone_table, chebyshev, p_cells, surrogate
from models.shape_backbone import load_table


@pytest.mark.parametrize("m", [2, 8, 16, 24])
def test_basis_against_clenshaw(m):
    nu = np.linspace(-1.0, 1.0, 4001)
    got, slope = chebyshev.basis_and_slope(jnp.asarray(nu), m)
    ref = np.stack([npcheb.chebval(nu, np.eye(m)[k]) for k in range(m)], -1)
    dref = np.stack([npcheb.chebval(nu, npcheb.chebder(np.eye(m)[k])) if k else 0 * nu
                     for k in range(m)], -1)
    # rounding of the monomial form grows like (1 + sqrt 2)^k (module doc)
    tol = 1e-15 * (1.0 + np.sqrt(2.0)) ** np.arange(m) * 8
    assert np.all(np.abs(np.asarray(got) - ref) <= tol)
    assert np.all(np.abs(np.asarray(slope) - dref) <= tol * (1 + np.arange(m) ** 2))
    assert np.all(np.isfinite(np.asarray(slope)))


def test_basis_above_max_terms_uses_the_recurrence():
    m = chebyshev.MAX_TERMS + 8
    nu = np.linspace(-1.0, 1.0, 501)
    ref = np.stack([npcheb.chebval(nu, np.eye(m)[k]) for k in range(m)], -1)
    assert np.max(np.abs(np.asarray(chebyshev.basis(jnp.asarray(nu), m)) - ref)) < 1e-12


def _tables():
    pre = lambda n: n - 1.0  # noqa: E731 - the power law's prefactor
    return [("jkr", load_table("jkr"), None), ("dmt", load_table("dmt"), None),
            ("powerlaw", backbone_table.load_table(), pre),
            ("greenwood_williamson", load_table("greenwood_williamson"), None)]


@pytest.mark.parametrize("name,table,pre", _tables(), ids=lambda v: v if isinstance(v, str)
                         else "")
def test_hand_derivatives_against_finite_differences(name, table, pre):
    """d/dx and d/dp of the lookup (one p for all points, as the samplers call it, and one
    p per row) against central differences of its own value, at random points."""
    lo, hi = (float(v) for v in table["p_range"])
    rng = np.random.default_rng(7)
    x = jnp.asarray(rng.uniform(0.02, 1.95, (6, 9)))
    p_rows = jnp.asarray(rng.uniform(lo + 0.01 * (hi - lo), hi - 0.01 * (hi - lo), (6, 1)))
    f = lambda xx, pp: surrogate.evaluate(table, xx, pp, prefactor=pre)  # noqa: E731
    h = 1e-6
    for p in (p_rows[2, 0], p_rows):
        gx, gp = jax.grad(lambda xx, pp: jnp.sum(f(xx, pp)), (0, 1))(x, p)
        fdx = (f(x + h, p) - f(x - h, p)) / (2 * h)
        if jnp.ndim(p) == 0:
            fdp = jnp.sum(f(x, p + h) - f(x, p - h)) / (2 * h)
        else:
            fdp = jnp.sum(f(x, p + h) - f(x, p - h), axis=1, keepdims=True) / (2 * h)
        # a point within h of a knot or of the contact-loss amplitude sees the C1 seam in
        # its difference quotient; the quotients' own error is ~1e-9
        np.testing.assert_allclose(np.asarray(gx), np.asarray(fdx), rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(np.asarray(gp), np.asarray(fdp), rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("name,table,pre", _tables(), ids=lambda v: v if isinstance(v, str)
                         else "")
def test_gradients_finite_at_the_table_edges(name, table, pre):
    lo, hi = (float(v) for v in table["p_range"])
    x = jnp.asarray([0.0, 1e-12, 0.5, 1.0, 2.0, 2.5])
    for p in (lo, hi, lo - 1.0, hi + 1.0):
        val, grad = jax.value_and_grad(
            lambda xx, pp: jnp.sum(surrogate.evaluate(table, xx, pp, prefactor=pre)),
            (0, 1))(x, jnp.asarray(p))
        assert np.isfinite(val) and np.all(np.isfinite(grad[0])) and np.isfinite(grad[1])


def test_knots_not_graded_as_built_are_refused():
    table = dict(load_table("jkr"))
    table["u_knots"] = np.linspace(0.0, 1.0, table["u_knots"].size)
    with pytest.raises(ValueError, match="u knots"):
        p_cells.amplitude_cell(table, jnp.asarray([0.5]), jnp.asarray(1.0))
