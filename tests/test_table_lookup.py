"""The table lookups' fast evaluation: the Chebyshev basis from powers, the closed-form
knot location, the patches of a two-coordinate table (models.tables.patches_2d) and the
derivatives written by hand (models.tables.one_shape, models.tables.hermite_cells, models.tables.patches_2d), each
against an independent reference (numpy's Clenshaw sums, finite differences)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from numpy.polynomial import chebyshev as npcheb

from beadrod.models.tables import chebyshev, hermite_cells, patches_2d, powerlaw_backbone, surrogate
from beadrod.models.tables.shape_read import load_table


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
            ("powerlaw", powerlaw_backbone.load_table(), pre),
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
        hermite_cells.amplitude_cell(table, jnp.asarray([0.5]), jnp.asarray(1.0))


def _global_interpolant(table, x, p, q):
    """A two-coordinate table's value from its global Chebyshev interpolant, written
    independently of the lookup: numpy's chebval2d, cells by searchsorted on the stored
    knots."""
    coef = np.concatenate([table["coef_contact"], table["coef_flight"]], axis=1)
    coef = np.moveaxis(coef, (2, 3), (0, 1))                  # (m, m_q, 4, cells)
    (p_lo, p_hi), (q_lo, q_hi) = table["p_range"], table["q_range"]
    uk, vk, x_max = table["u_knots"], table["v_knots"], float(table["x_max"])
    out = np.empty(x.size)
    for k in range(x.size):
        nu = (2.0 * p[k] - p_lo - p_hi) / (p_hi - p_lo)
        nq = (2.0 * q[k] - q_lo - q_hi) / (q_hi - q_lo)
        xc = npcheb.chebval2d(nu, nq, table["xc_cheb"])
        cells = npcheb.chebval2d(nu, nq, coef)
        if x[k] <= xc:
            z, knots, first = x[k] / xc, uk, 0
        else:
            z, knots, first = (x[k] - xc) / (x_max - xc), vk, uk.size - 1
        i = int(np.clip(np.searchsorted(knots, z, side="right") - 1, 0, knots.size - 2))
        d, a = z - knots[i], cells[:, first + i]
        y = ((a[0] * d + a[1]) * d + a[2]) * d + a[3]
        out[k] = x[k] ** 2 * y if x[k] <= xc else y
    return out, xc


def test_patches_against_the_global_interpolant():
    """models.tables.patches_2d: Maugis-Dugdale's table on its (p, q) patches (how a fit reads
    it) against its global Chebyshev interpolant, 3000 random points over the whole
    table and 1000 within 1e-3 of the contact-loss corner on either side: within the
    module's stated ERROR (measured 4.3e-7; the table's own error is 1e-5)."""
    table = load_table("maugis_dugdale")
    rng = np.random.default_rng(11)
    n = 3000
    x = rng.uniform(0.0, float(table["x_max"]), n)
    p, q = rng.uniform(*table["p_range"], n), rng.uniform(*table["q_range"], n)
    one = jax.jit(jax.vmap(lambda a, b, c: surrogate.evaluate(table, a, b, q=c)))
    ref, _ = _global_interpolant(table, x, p, q)
    assert np.max(np.abs(np.asarray(one(x, p, q)) - ref)) <= patches_2d.ERROR
    xc = np.array([_global_interpolant(table, np.ones(1), p[k:k + 1], q[k:k + 1])[1]
                   for k in range(1000)])
    xk = np.clip(xc + rng.uniform(-1e-3, 1e-3, 1000), 0.0, float(table["x_max"]))
    ref, _ = _global_interpolant(table, xk, p[:1000], q[:1000])
    assert np.max(np.abs(np.asarray(one(xk, p[:1000], q[:1000])) - ref)) <= patches_2d.ERROR


def test_patch_derivatives_against_finite_differences():
    """d/dx, d/dp and d/dq of the patch lookup at one (p, q) for all points (the
    sampler's case) against central differences of its own value, at (p, q) inside
    patches and on a patch edge, and finite at the table's corners and beyond them."""
    table = load_table("maugis_dugdale")
    (p_lo, p_hi), (q_lo, q_hi) = table["p_range"], table["q_range"]
    rng = np.random.default_rng(5)
    x = jnp.asarray(rng.uniform(0.02, 1.95, 40))
    f = lambda xx, pp, qq: surrogate.evaluate(table, xx, pp, q=qq)  # noqa: E731
    g = jax.grad(lambda xx, pp, qq: jnp.sum(f(xx, pp, qq)), (0, 1, 2))
    edge_p = p_lo + (p_hi - p_lo) * 5 / patches_2d.P_PATCHES + 1e-3   # just past an edge
    h = 1e-6
    for p, q in ((rng.uniform(p_lo, p_hi), rng.uniform(q_lo, q_hi)), (edge_p, 0.3)):
        p, q = jnp.asarray(p), jnp.asarray(q)
        gx, gp, gq = g(x, p, q)
        fdx = (f(x + h, p, q) - f(x - h, p, q)) / (2 * h)
        fdp = jnp.sum(f(x, p + h, q) - f(x, p - h, q)) / (2 * h)
        fdq = jnp.sum(f(x, p, q + h) - f(x, p, q - h)) / (2 * h)
        np.testing.assert_allclose(np.asarray(gx), np.asarray(fdx), rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(float(gp), float(fdp), rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(float(gq), float(fdq), rtol=1e-5, atol=1e-7)
    xe = jnp.asarray([0.0, 1e-12, 0.5, 1.0, 2.0, 2.5])
    for p in (p_lo, p_hi, p_lo - 1.0, p_hi + 1.0):
        for q in (q_lo, q_hi, q_lo - 1.0, q_hi + 1.0):
            val, grads = jax.value_and_grad(lambda a, b, c: jnp.sum(f(a, b, c)), (0, 1, 2))(
                xe, jnp.asarray(p), jnp.asarray(q))
            assert np.isfinite(val) and all(np.all(np.isfinite(v)) for v in grads)


def test_patches_refuse_a_table_with_pieces_in_p():
    table = {k: v for k, v in load_table("maugis_dugdale").items() if not k.startswith("_")}
    table["p_edges"] = np.asarray([*table["p_range"][:1], 0.0, *table["p_range"][1:]])
    with pytest.raises(ValueError, match="pieces in p"):
        patches_2d.resample(table)
