"""Tabulated backbone against the exact energy-integral backbone and closed forms.

References: models.ladder.backbone.backbone_shift (48 Gauss nodes; 128 within 0.05 of the
contact-loss amplitude x_c, where 48 nodes are not accurate enough), the closed-form
piecewise-linear oscillator (n = 1), and the Lindstedt coefficient by hand. The exact
backbone is evaluated once per module, in two batches (one compile per node count).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

from beadrod.models.ladder.backbone import backbone_shift, lindstedt_shift, powerlaw_orbit
from beadrod.models.tables.powerlaw_backbone import (
    SPEC,
    X_MAX,
    backbone_shift_fast,
    contact_loss_amplitude,
    load_table,
)
from beadrod.models.tables.surrogate import chebyshev_nodes, spline_coefficients, to_chebyshev

KINK_N = np.array([1.25, 1.5, 2.0, 3.0])
KINK_OFF = np.array([-1e-3, -1e-5, -1e-6, 1e-6, 1e-5, 1e-3])
GRID_N = [1.5, 2.0, 3.0]          # x = adversarial amplitudes at fixed n
GRID_X = [1e-3, 0.02, 0.3, X_MAX]
FD_PTS = [(0.3, 1.2), (0.6, 1.5), (1.4, 1.5), (0.4, 2.7), (1.8, 2.2), (1.3, 1.05)]
FD_H = 1e-5
REBUILD = [(5, 0), (31, 11), (62, 23)]   # (knot i, n node j)


def _exact_kink(n):
    """x_c(n) = a1 at qmax_c = (n+1)^(1/n) - 1 from the exact orbit (just below qmax_c)."""
    qc = (n + 1.0) ** (1.0 / n) - 1.0
    return np.asarray(jax.jit(jax.vmap(powerlaw_orbit))(jnp.asarray(qc * (1 - 1e-12)), jnp.asarray(n))[1])


@pytest.fixture(scope="module")
def ref():
    rng = np.random.default_rng(20261123)
    tab = load_table()
    xr, nr = rng.uniform(0, X_MAX, 40), rng.uniform(1, 3, 40)
    xg, ng = (a.ravel() for a in np.meshgrid(GRID_X, GRID_N))
    xck = _exact_kink(KINK_N)
    xk = (xck[:, None] + KINK_OFF).ravel()
    nk = np.repeat(KINK_N, KINK_OFF.size)
    xf = np.concatenate([[x - FD_H, x + FD_H, x, x] for x, _ in FD_PTS])
    nf = np.concatenate([[n, n, n - FD_H, n + FD_H] for _, n in FD_PTS])
    uk, vk, nn, xcn = tab["u_knots"], tab["v_knots"], tab["n_nodes"], tab["xc_nodes"]
    xa = np.array([uk[i] * xcn[j] for i, j in REBUILD])
    xb = np.array([xcn[j] + vk[i] * (X_MAX - xcn[j]) for i, j in REBUILD])
    nrb = np.array([nn[j] for _, j in REBUILD])
    x = np.concatenate([xr, xg, xk, xf, xa, xb])
    n = np.concatenate([nr, ng, nk, nf, nrb, nrb])
    xc = np.asarray(contact_loss_amplitude(n))
    fine = np.abs(x - xc) < 0.05
    s = np.empty_like(x)
    s[fine] = np.asarray(backbone_shift(x[fine], n[fine], nodes=128))
    s[~fine] = np.asarray(backbone_shift(x[~fine], n[~fine]))
    parts = np.cumsum([0, xr.size, xg.size, xk.size, xf.size, xa.size, xb.size])
    keys = ["random", "grid", "kink", "fd", "rebuild_a", "rebuild_b"]
    out = {k: (x[a:b], n[a:b], s[a:b]) for k, a, b in zip(keys, parts[:-1], parts[1:])}
    out["xc"] = xck
    return out


@pytest.mark.parametrize("part", ["random", "grid", "kink"])
def test_matches_exact_backbone(ref, part):
    x, n, s = ref[part]
    err = np.abs(np.asarray(backbone_shift_fast(x, n)) - s)
    assert err.max() <= 1e-6
    if part == "random":  # the measured accuracy is far inside the target
        assert err.max() <= 1e-7


def test_contact_loss_amplitude(ref):
    # n = 1: the orbit through q = -1 at rest is the harmonic q = cos t, a1 = qmax = 1
    # (the table places the kink at qmax_c (1 - 1e-12): x_c lower by ~1e-12)
    assert float(contact_loss_amplitude(1.0)) == pytest.approx(1.0, abs=3e-12)
    np.testing.assert_allclose(np.asarray(contact_loss_amplitude(KINK_N)), ref["xc"],
                               atol=1e-11)


def test_small_amplitude_is_lindstedt():
    # (n-1)(n-2)/16 - 5(n-1)^2/48 = (n-1)[3(n-2) - 5(n-1)]/48 = -(n-1)(2n+1)/48
    n = np.array([1.001, 1.2, 1.5, 2.0, 2.6, 3.0])
    c2 = -(n - 1) * (2 * n + 1) / 48
    np.testing.assert_allclose(np.asarray(lindstedt_shift(1.0, n)), c2, rtol=1e-14)
    for x in (1e-6, 1e-4):
        s = np.asarray(backbone_shift_fast(x, n))
        np.testing.assert_allclose(s / x**2, c2, rtol=1e-4)
    assert float(backbone_shift_fast(0.0, 1.7)) == 0.0


def test_small_amplitude_relative_error(ref):
    x, n, s = ref["grid"]
    small = x < 0.05
    f = np.asarray(backbone_shift_fast(x[small], n[small]))
    np.testing.assert_allclose(f, s[small], rtol=1e-4)


_GL = np.polynomial.legendre.leggauss(30)


def _linear_flight_orbit(a):
    """n = 1, qmax = a > 1: harmonic arc q = a cos t to q = -1, then free flight q'' = 1.

    Half period theta + v with theta = arccos(-1/a), v = sqrt(a^2 - 1); returns (omega, a1).
    """
    th, v = np.arccos(-1 / a), np.sqrt(a * a - 1)
    half = th + v
    om = np.pi / half
    arc = a / 2 * (np.sin((1 + om) * th) / (1 + om) + th * np.sinc((1 - om) * th / np.pi))
    s = v * (_GL[0] + 1) / 2
    fl = v / 2 * np.sum(_GL[1] * (-1 - v * s + s * s / 2) * np.cos(om * (th + s)))
    return om, 2 / half * (arc + fl)


def test_linear_spring_with_contact_loss_closed_form():
    # independent of the quadrature: the bilinear (spring / free flight) oscillator
    # below contact loss the linear spring has no shift at all
    assert np.all(np.asarray(backbone_shift_fast(np.linspace(0, 1 - 1e-9, 11), 1.0)) == 0.0)
    for x in 1 + np.array([1e-8, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.3, 1.0]):
        a = brentq(lambda a, x=x: _linear_flight_orbit(a)[1] - x, 1 + 1e-16, 3.0,
                   xtol=1e-15, rtol=1e-15)
        s_ref = _linear_flight_orbit(a)[0] - 1
        assert float(backbone_shift_fast(x, 1.0)) == pytest.approx(s_ref, abs=1e-7)


def test_gradients_match_finite_differences_of_exact(ref):
    _, _, s = ref["fd"]
    s = s.reshape(-1, 4)
    grad = jax.jit(jax.vmap(jax.grad(backbone_shift_fast, argnums=(0, 1))))
    gx, gn = grad(jnp.array([p[0] for p in FD_PTS]), jnp.array([p[1] for p in FD_PTS]))
    fdx = (s[:, 1] - s[:, 0]) / (2 * FD_H)
    fdn = (s[:, 3] - s[:, 2]) / (2 * FD_H)
    np.testing.assert_allclose(np.asarray(gx), fdx, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(np.asarray(gn), fdn, rtol=1e-5, atol=1e-7)


def test_gradients_finite_everywhere_and_continuous_at_kink():
    grad = jax.jit(jax.vmap(jax.grad(backbone_shift_fast, argnums=(0, 1))))
    n = jnp.array([1.0, 1.0, 1.0, 1.5, 3.0, 3.0, 2.0, 1.0 - 5e-10])
    x = jnp.array([0.0, 1.0, X_MAX, 0.0, X_MAX, 1e-12, 0.5, 0.5])
    gx, gn = grad(x, n)
    assert np.all(np.isfinite(gx)) and np.all(np.isfinite(gn))
    # C1 across x_c (the exact backbone is C1 there; the flight spline is clamped to the
    # contact side's slope): one-sided slopes in x and in n agree
    for nk in (1.0, 1.5, 2.5):
        xc = float(contact_loss_amplitude(nk))
        gx, gn = grad(jnp.array([xc - 1e-10, xc + 1e-10]), jnp.full(2, nk))
        assert float(gx[0]) == pytest.approx(float(gx[1]), abs=1e-6)
        assert float(gn[0]) == pytest.approx(float(gn[1]), abs=1e-6)


def test_jit_vmap_broadcast_and_domain():
    x = jnp.linspace(0, X_MAX, 12).reshape(3, 4)
    direct = backbone_shift_fast(x, 1.5)
    assert direct.shape == (3, 4)
    jv = jax.jit(jax.vmap(backbone_shift_fast, in_axes=(0, None)))(x, 1.5)
    np.testing.assert_allclose(np.asarray(jv), np.asarray(direct), rtol=0, atol=1e-15)
    assert backbone_shift_fast(0.5, jnp.array([1.5, 2.0, 2.5])).shape == (3,)
    bad = backbone_shift_fast(jnp.array([-0.1, X_MAX + 1e-6, 0.5, 0.5, 0.5]),
                              jnp.array([1.5, 1.5, 0.99, 3.01, 3.0 + 5e-10]))
    assert np.all(np.isnan(np.asarray(bad[:4]))) and np.isfinite(float(bad[4]))
    # NaN outside the domain must not poison gradients inside it
    g = jax.grad(lambda v: jnp.nansum(backbone_shift_fast(v, 1.5)))(jnp.array([0.5, 2.5]))
    assert np.all(np.isfinite(np.asarray(g)))


def test_table_matches_fresh_rebuild(ref):
    tab = load_table()
    q = np.array([tab["q_contact"][i, j] for i, j in REBUILD])
    s = np.array([tab["s_flight"][i, j] for i, j in REBUILD])
    xa, na, sa = ref["rebuild_a"]
    _, _, sb = ref["rebuild_b"]
    np.testing.assert_allclose(sa / ((na - 1) * xa**2), q, rtol=1e-11)
    np.testing.assert_allclose(sb, s, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(_exact_kink(tab["n_nodes"][:3]), tab["xc_nodes"][:3], rtol=1e-13)
    # stored coefficients are the fit of the stored samples
    fit = to_chebyshev(spline_coefficients(tab["v_knots"], tab["s_flight"],
                                           tab["kink_slope"]), chebyshev_nodes(SPEC)[0])
    np.testing.assert_allclose(fit, tab["coef_flight"], rtol=1e-12, atol=1e-14)
    assert sum(v.nbytes for v in tab.values()) < 2e6


@pytest.mark.slow
def test_exhaustive_against_exact():
    rng = np.random.default_rng(7)
    x, n = rng.uniform(0, X_MAX, 2000), rng.uniform(1, 3, 2000)
    nk = np.linspace(1.02, 3.0, 12)
    off = np.array([-3e-2, -3e-3, -3e-4, -3e-5, -3e-6, 3e-6, 3e-5, 3e-4, 3e-3, 3e-2])
    x = np.concatenate([x, (_exact_kink(nk)[:, None] + off).ravel()])
    n = np.concatenate([n, np.repeat(nk, off.size)])
    xc = np.asarray(contact_loss_amplitude(n))
    fine = np.abs(x - xc) < 0.05
    s = np.empty_like(x)
    s[fine] = np.asarray(backbone_shift(x[fine], n[fine], nodes=128))
    s[~fine] = np.asarray(backbone_shift(x[~fine], n[~fine]))
    err = np.abs(np.asarray(backbone_shift_fast(x, n)) - s)
    away = np.abs(x - xc) > 0.01
    print(f"max abs error {err.max():.3g} at x = {x[err.argmax()]:.6f}, n = {n[err.argmax()]:.4f};"
          f" {err[away].max():.3g} farther than 0.01 from x_c")
    assert err.max() <= 1e-6
    # the |x - x_c|^(n + 1/2) term limits the cubic pieces next to the kink (worst for
    # n -> 1); elsewhere the table is far more accurate
    assert err[away].max() <= 2e-8
