"""The Maugis-Dugdale oscillator in parametric form (models.laws.maugis_dugdale.orbit) against
the generic quadrature of the law's force (each force a bracketed root solve, itself
tested against mpmath in test_maugis_dugdale.py): the mean restoring force over intervals
(short, long, straddling the contact edge), P', the flight acceleration, the Lindstedt
coefficient; the root against the module's own; and the backbone's JKR (lam -> inf) and DMT
(lam -> 0) limits (slow)."""

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from beadrod.models.ladder import generic
from beadrod.models.laws import dmt, jkr, maugis_dugdale
from beadrod.models.laws.maugis_dugdale import orbit

R_BEAD, RHO, NU, G = 7.938e-3, 7700.0, 0.27, 9.80665
MASS = 4.0 / 3.0 * math.pi * R_BEAD**3 * RHO
LOAD = MASS * G
ES = 200e9 / (2 * (1 - NU**2))
# the generic quadrature of F
PLAIN = dataclasses.replace(maugis_dugdale.LAW, physics=dataclasses.replace(
    maugis_dugdale.LAW.physics, restoring_force=None))

A = jnp.array([-1.0, -1.0, -0.5, 0.0, 0.3, 0.999, -0.9999999, -1.5, -2.0, 0.0])
B = jnp.array([0.0, 50.0, 1.5, 2.0, 0.3000001, 1.0, -0.9999998, 0.5, -1.2, 1e-13])
Q = jnp.array([-1.5, -1.0, -0.99, -0.3, 0.0, 0.4, 3.0, 40.0])


def _kw(gamma, lam):
    return dict(e_star=ES, radius=R_BEAD, gamma=gamma, lam=lam, load=LOAD, mass=MASS)


@jax.jit
def _both_forms(gamma, lam):
    kw = _kw(gamma, lam)
    d0 = maugis_dugdale.contact.static_overlap(LOAD, e_star=ES, radius=R_BEAD, gamma=gamma, lam=lam)
    dp, div, acc = generic.restoring_force(maugis_dugdale.LAW, delta0=d0, **kw)
    gdp, gdiv, gacc = generic.restoring_force(PLAIN, delta0=d0, **kw)
    return (div(A, B), div(B, A), dp(Q), acc), (gdiv(A, B), gdiv(-1.0, B), gdp(Q), gacc)


def test_restoring_force_matches_generic_quadrature_of_the_force():
    """gamma 0.05-2.5 J/m^2 (load ratio F0/Fc 0.4-19), lam 0.1-100."""
    for gamma in (0.05, 0.7, 2.5):
        for lam in (0.1, 0.9, 3.0, 100.0):
            (div, div_rev, dp, acc), (gdiv, g_edge, gdp, gacc) = (
                [np.asarray(v) for v in out] for out in _both_forms(gamma, lam))
            assert float(acc) == pytest.approx(float(gacc), rel=1e-12)
            # intervals across the contact edge: the generic rule integrates over the jump
            # of P' there (to ~1e-4); the reference splits them at q = -1 (flight below)
            ref = gdiv.copy()
            cross = np.asarray((A < -1.0) & (B > -1.0))
            a, b = np.asarray(A)[cross], np.asarray(B)[cross]
            ref[cross] = ((-1.0 - a) * -float(gacc) + (b + 1.0) * g_edge[cross]) / (b - a)
            # 1e-9: the generic rule's own error on the widest interval (its 97 tanh-sinh
            # nodes; 16 and 48 Gauss nodes of the parametric form agree to 3e-14)
            np.testing.assert_allclose(div, ref, rtol=1e-9, atol=1e-12, err_msg=(gamma, lam))
            np.testing.assert_allclose(div_rev, ref, rtol=1e-9, atol=1e-12)   # symmetric
            np.testing.assert_allclose(dp, gdp, rtol=1e-11, atol=1e-13)


@jax.jit
def _lindstedt_both(lam):
    kw = _kw(0.7, lam)
    d0 = maugis_dugdale.contact.static_overlap(LOAD, e_star=ES, radius=R_BEAD, gamma=0.7, lam=lam)
    return (generic.lindstedt_coefficient(maugis_dugdale.LAW, delta0=d0, **kw),
            generic.lindstedt_coefficient(PLAIN, delta0=d0, **kw))


@pytest.mark.slow  # in `-m slow`, run before an issue is resolved (keeps CI under 12 min)
def test_lindstedt_coefficient_and_its_derivatives_through_the_root():
    """c = 3 a3/8 - 5 a2^2/12 needs P''' at 0: through the custom_jvp root, to every order."""
    for lam in (0.2, 5.0):
        c, c_ref = (float(v) for v in _lindstedt_both(lam))
        assert c == pytest.approx(c_ref, rel=1e-10)
        assert -0.05 < c < -0.03   # softening, near Hertz's -1/24


@jax.jit
def _roots(d, lam):
    grads = [jax.grad(f, argnums=(0, 1))(1.3, lam) for f in (
        lambda a, b: orbit.log_angle_from_overlap(a, b),
        lambda a, b: jnp.log(maugis_dugdale.contact.angle_from_overlap(a, b)))]
    return orbit.log_angle_from_overlap(d, lam), maugis_dugdale.contact.angle_from_overlap(d, lam), grads


def test_root_matches_the_bracketed_solve():
    d = jnp.concatenate([jnp.array([0.0, 1e-9]), jnp.logspace(-3, 8, 23)])
    for lam in (0.1, 0.938, 1.0, 30.0, 200.0):
        u, th, (g, h) = _roots(d, lam)
        np.testing.assert_allclose(jnp.exp(u), th, rtol=1e-12)
        for a, b in zip(g, h):   # the implicit derivatives in Delta and lam
            assert float(a) == pytest.approx(float(b), rel=1e-9)


def _backbone_gap(law_kw, other, lam, x):
    kw = _kw(law_kw, lam)
    # the exact root solve: lam = 200 and 0.01 lie outside the law's parameter domain,
    # where its tabulated static state is NaN (the generic backbone takes any lam)
    d0 = maugis_dugdale.contact.static_overlap(LOAD, e_star=ES, radius=R_BEAD, gamma=law_kw, lam=lam)
    s_md = generic.backbone_shift(maugis_dugdale.LAW, x, delta0=d0, nodes=24, **kw)
    okw = dict(e_star=ES, radius=R_BEAD, gamma=law_kw, load=LOAD, mass=MASS)
    s_other = generic.backbone_shift(other.LAW, x, delta0=other.LAW.overlap(**okw), nodes=24,
                                     **okw)
    return float(jnp.max(jnp.abs(s_md - s_other)))


@pytest.mark.slow
def test_backbone_tends_to_jkr_and_dmt():
    """(slow: three generic backbones, about a minute each to compile) lam -> inf: JKR;
    lam -> 0: DMT (this project's DMT, the same contact edge delta = 0)."""
    x = jnp.array([0.3, 0.9, 1.5])
    j50, j200 = (_backbone_gap(0.7, jkr, lam, x) for lam in (50.0, 200.0))
    assert j200 < 2e-4 and j200 < j50 / 4, (j50, j200)
    d1, d01 = (_backbone_gap(0.7, dmt, lam, x) for lam in (0.1, 0.01))
    assert d01 < d1 / 2, (d1, d01)
