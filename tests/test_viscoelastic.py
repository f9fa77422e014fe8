"""Viscoelastic (Brilliantov / Kuwabara-Kono) law and the paper's Eq. 25 (issue 2, items 4, 10).

References here are independent of models/: closed forms typed from the paper, scipy/mpmath
quadrature, and the finite-difference recipe the paper most likely used.
"""

import math

import jax
import jax.numpy as jnp
import mpmath as mp
import numpy as np
import pytest
from scipy import integrate

from beadrod.models.laws import viscoelastic

# The paper's setup (Secs. 2, 4.1): steel bead r = 7.938 mm, rho = 7700, nu = 0.27.
R_BEAD, RHO, NU, G = 7.938e-3, 7700.0, 0.27, 9.80665
MASS = 4.0 / 3.0 * math.pi * R_BEAD**3 * RHO
LOAD = MASS * G


def hertz_f0(young):
    """Hertz linear resonance typed from the paper's Eqs. 3, 7 (independent of models/)."""
    es = young / (2 * (1 - NU**2))
    d0 = (3 * LOAD / (4 * es * math.sqrt(R_BEAD))) ** (2 / 3)
    return math.sqrt(2 * es * math.sqrt(R_BEAD * d0) / MASS) / (2 * math.pi), d0, es


def a_paper(eta, young, nu):
    """Paper Eq. 9 typed in, eta1 = eta2 = eta."""
    return (1 / young) * (1 + nu) / (1 - nu) * (4 / 3 * eta * (1 - nu + nu**2) + eta * (1 - 2 * nu) ** 2)


# --- paper numbers --------------------------------------------------------------------------

def test_damping_constant_paper_value():
    a = float(viscoelastic.damping_constant(eta1=1.05e6, young=210e9, poisson=NU))
    assert a == pytest.approx(a_paper(1.05e6, 210e9, NU), rel=1e-14)
    assert round(a, 6) == pytest.approx(1.1e-5)  # paper: A = 1.1e-5 (E = 210 GPa)
    # eta2 enters with (1 - 2nu)^2 only
    a2 = float(viscoelastic.damping_constant(eta1=1.05e6, eta2=0.0, young=210e9, poisson=NU))
    assert a2 == pytest.approx(1 / 210e9 * 1.27 / 0.73 * 4 / 3 * 1.05e6 * (1 - NU + NU**2))


def test_q_paper_values():
    f0, d0, es = hertz_f0(210e9)
    w0 = 2 * math.pi * f0
    a = float(viscoelastic.damping_constant(eta1=1.05e6, young=210e9, poisson=NU))
    q = float(viscoelastic.linear_q(damping_constant=a, omega0=w0))
    # paper Eq. 30 typed in: Q = omega0 m / (2 E* A (R delta0)^(1/2))
    q30 = w0 * MASS / (2 * es * a * math.sqrt(R_BEAD * d0))
    assert q == pytest.approx(q30, rel=1e-12)
    assert round(q) == 5  # paper: Q = 5 (5.32)
    assert float(viscoelastic.linear_inverse_q(damping_constant=a, omega0=w0)) == pytest.approx(1 / q)
    # paper: Q = 20 <-> eta ~ 0.3 MPa s, Q = 100 <-> 55 kPa s
    eta20 = float(viscoelastic.eta_from_q(20.0, omega0=w0, young=210e9, poisson=NU))
    eta100 = float(viscoelastic.eta_from_q(100.0, omega0=w0, young=210e9, poisson=NU))
    assert round(eta20 / 1e6, 1) == 0.3  # 0.279 MPa s
    assert eta100 == pytest.approx(55e3, rel=0.02)  # 55.8 kPa s
    q55 = 1 / (w0 * a_paper(55e3, 210e9, NU))
    assert round(q55, -1) == 100  # 101.5
    assert 1 / (w0 * a_paper(0.3e6, 210e9, NU)) == pytest.approx(18.6, abs=0.05)  # rounds to 20
    # inverse maps invert
    assert float(viscoelastic.eta_from_damping_constant(a, young=210e9, poisson=NU)) == pytest.approx(1.05e6)


def test_kuwabara_kono_cited_case():
    """Paper Sec. 7.1, ref. [10]: E = 193 GPa, nu = 0.35, two beads r1 = r2 = 1.27 cm."""
    young, nu, r = 193e9, 0.35, 1.27e-2
    es = young / (2 * (1 - nu**2))  # two identical bodies
    rad = r / 2  # 1/R = 1/r1 + 1/r2
    kn = 4 / 3 * es * math.sqrt(rad)
    assert kn == pytest.approx(1.17e10, rel=5e-3)  # paper k_n = 1.17e10: reproduced (1.1684e10)
    a = viscoelastic.damping_constant(eta1=1.05e6, young=young, poisson=nu)
    gn = float(viscoelastic.kuwabara_kono_gamma(e_star=es, radius=rad, damping_constant=a))
    assert gn == pytest.approx(1.5 * a_paper(1.05e6, young, nu) * kn, rel=1e-12)
    # paper gamma_n = 7.8e4 is NOT reproduced: Eqs. 8-9 give 2.22e5 (x2.84); see docs.
    assert gn == pytest.approx(2.218e5, rel=1e-3)
    assert not (7.0e4 < gn < 8.5e4)


# --- force ----------------------------------------------------------------------------------

def test_force_sign_and_clip():
    es, rad, a = 1.1e11, R_BEAD, 1e-5
    kn = 4 / 3 * es * math.sqrt(rad)
    d = 50e-9
    for v in (0.0, 1e-3, -1e-3):
        f = float(viscoelastic.force(d, v, e_star=es, radius=rad, damping_constant=a))
        assert f == pytest.approx(kn * (d**1.5 + 1.5 * a * d**0.5 * v), rel=1e-13)
    # fast unloading: raw Eq. 8 goes tensile, the clipped variant does not
    v = -0.02
    raw = float(viscoelastic.force(d, v, e_star=es, radius=rad, damping_constant=a))
    assert raw < 0
    assert float(viscoelastic.force(d, v, e_star=es, radius=rad, damping_constant=a, clip=True)) == 0.0
    # contact lost
    assert float(viscoelastic.force(-1e-9, 1.0, e_star=es, radius=rad, damping_constant=a)) == 0.0


def test_force_linearisation_gives_q():
    """dF/d(delta_dot) at (delta0, 0) = A K0, so m x'' + A K0 x' + K0 x = 0 (paper Eq. 29)."""
    f0, d0, es = hertz_f0(210e9)
    a = a_paper(1.05e6, 210e9, NU)
    c = jax.grad(lambda v: viscoelastic.force(d0, v, e_star=es, radius=R_BEAD, damping_constant=a))(0.0)
    k0 = 2 * es * math.sqrt(R_BEAD * d0)
    assert float(c) == pytest.approx(a * k0, rel=1e-12)


def test_gradients_finite_at_zero_viscosity():
    def f(eta, d, v):
        a = viscoelastic.damping_constant(eta1=eta, young=210e9, poisson=NU)
        return viscoelastic.force(d, v, e_star=1.1e11, radius=R_BEAD, damping_constant=a, clip=True)

    for d in (0.0, 50e-9):
        g = jax.grad(f, argnums=(0, 1, 2))(0.0, d, 0.01)
        assert all(np.isfinite(float(x)) for x in g)
    g = jax.grad(lambda a: viscoelastic.linear_inverse_q(damping_constant=a, omega0=1.7e4))(0.0)
    assert float(g) == pytest.approx(1.7e4)
    g = jax.grad(lambda eta: viscoelastic.eta_from_q(eta, omega0=1.7e4, young=2e11, poisson=NU))(20.0)
    assert np.isfinite(float(g))


# --- Eq. 25: the extra term vanishes under every well-defined reading ------------------------

XS = [0.05, 0.3, 0.7, 0.95, 1.0]


def pv_period(f, poles):
    """PV of Int_0^2pi f over simple poles (scipy QAWC on pieces), f regular elsewhere."""
    total = 0.0
    edges = [0.0, math.pi, 2 * math.pi]
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = [p for p in poles if lo < p < hi]
        if inside:
            c = inside[0]

            def g(t, c=c):
                return f(t) * (t - c) if t != c else 0.0

            val, _ = integrate.quad(g, lo, hi, weight="cauchy", wvar=c, limit=200)
        else:
            val, _ = integrate.quad(f, lo, hi, limit=200, epsabs=1e-13)
        total += val
    return total


def pv_excision(f, eps):
    """PV by symmetric excision of the poles at pi/2, 3pi/2, mpmath at 40 digits (a second,
    independent method); the pole positions are computed at the working precision."""
    with mp.workdps(40):
        eps = mp.mpf(eps)
        pts = [mp.mpf(0)]
        for p in (mp.pi / 2, 3 * mp.pi / 2):
            pts += [p - eps, p + eps]
        pts.append(2 * mp.pi)
        total = mp.mpf(0)
        for lo, hi in zip(pts[0::2], pts[1::2]):
            mid = (lo + hi) / 2  # extra nodes near both ends of each piece
            total += mp.quad(f, [lo, lo + (mid - lo) / 1000, mid, hi - (hi - mid) / 1000, hi])
        return total


def test_pv_machinery_detects_nonzero():
    """Control: the same PV tools return a NONzero value when the symmetry is absent."""
    f = lambda t: math.exp(0.3 * math.cos(t) + 0.4 * math.sin(t)) * math.tan(t)
    a = pv_period(f, [math.pi / 2, 3 * math.pi / 2])
    b = pv_excision(lambda t: mp.exp(0.3 * mp.cos(t) + 0.4 * mp.sin(t)) * mp.tan(t), "1e-20")
    assert abs(a) > 0.1
    assert a == pytest.approx(float(b), abs=1e-9)


@pytest.mark.parametrize("x", XS)
def test_eq25_reading1_orbit_principal_value(x):
    """dh/ds along the orbit = h'(t)/s'(t); PV over the turning points."""
    def f(t):
        u = 1 + x * math.sin(t)
        dh = 0.5 * x**2 * math.cos(t) ** 2 / math.sqrt(u) - math.sqrt(u) * x * math.sin(t) if u > 0 else 0.0
        return dh / (x * math.cos(t))

    val = pv_period(f, [math.pi / 2, 3 * math.pi / 2])
    assert abs(val) < 1e-8
    if x in (0.3, 1.0):  # second method (slower): mpmath, symmetric excision
        ref = pv_excision(
            lambda t: (0.5 * x**2 * mp.cos(t) ** 2 / mp.sqrt(1 + x * mp.sin(t))
                       - mp.sqrt(1 + x * mp.sin(t)) * x * mp.sin(t)) / (x * mp.cos(t)),
            "1e-20")
        assert abs(float(ref)) < 1e-8


@pytest.mark.parametrize("x", XS)
def test_eq25_reading2_fixed_tau(x):
    """(1/sin t) d h/d(delta_a) at fixed t: poles at t = 0, pi; PV zero."""
    def f(t):
        u = 1 + x * math.sin(t)
        if u <= 0:  # x = 1, t = 3pi/2: both terms vanish there (bounded integrand)
            return 0.0
        dh_dx = 0.5 * math.sin(t) * x * math.cos(t) / math.sqrt(u) + math.sqrt(u) * math.cos(t)
        return dh_dx / math.sin(t)

    # shift the period so the poles at 0 and pi are interior: integrate over [-pi/2, 3pi/2]
    g = lambda t: f(t - math.pi / 2)
    val = pv_period(g, [math.pi / 2, 3 * math.pi / 2])
    assert abs(val) < 1e-8


@pytest.mark.parametrize("x", XS)
def test_eq25_reading3_in_phase_harmonic(x):
    """In-phase first harmonic of the dissipative force: Int (1+x sin t)^(1/2) cos t sin t dt."""
    val = mp.quad(lambda t: mp.sqrt(1 + x * mp.sin(t)) * mp.cos(t) * mp.sin(t),
                  [0, mp.pi / 2, mp.pi, 3 * mp.pi / 2, 2 * mp.pi])
    out = mp.quad(lambda t: mp.sqrt(1 + x * mp.sin(t)) * mp.cos(t) ** 2,
                  [0, mp.pi / 2, mp.pi, 3 * mp.pi / 2, 2 * mp.pi])
    assert abs(float(val)) < 1e-14
    assert float(out) > 1.0  # the quadrature component (damping) is not zero


@pytest.mark.parametrize("x", XS)
def test_eq25_reading4_fixed_velocity(x):
    """d/d(delta) at fixed velocity: Int (1 + x sin t)^(-1/2) cos t dt (integrable at x = 1)."""
    val, _ = integrate.quad(lambda t: math.cos(t) / math.sqrt(max(1 + x * math.sin(t), 1e-300)),
                            0, 2 * math.pi, points=[3 * math.pi / 2], limit=400)
    assert abs(val) < 1e-7


def test_shift_first_order_is_hertz():
    """The correct law: elliptic-integral Hertz shift, -0.05 at x = 1 (independent mpmath)."""
    for x in (0.1, 0.5, 1.0):
        ref = mp.quad(lambda t, x=x: mp.sqrt(1 + x * mp.sin(t)), [0, mp.pi, 3 * mp.pi / 2, 2 * mp.pi])
        ref = ref / (4 * mp.pi) - mp.mpf(1) / 2
        assert float(viscoelastic.shift_first_order(x)) == pytest.approx(float(ref), abs=1e-12)
    assert float(viscoelastic.shift_first_order(1.0)) == pytest.approx(-0.05, abs=0.005)


# --- the artefact: secant slopes on a uniform grid ------------------------------------------

def secant_extra(x, n_points):
    """The paper's Eq. 25 extra term / (A omega) by forward secants on linspace(0, 2pi, N)."""
    t = np.linspace(0.0, 2 * np.pi, n_points)
    h = np.sqrt(1 + x * np.sin(t)) * x * np.cos(t)
    s = x * np.sin(t)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.diff(h) / np.diff(s)
        return np.sum(r) * (t[1] - t[0]) / (4 * np.pi)


@pytest.mark.parametrize("x", [0.1, 0.5, 0.9, 0.99])
def test_secant_artefact_reproduces_paper_term(x):
    a, w = 1.1e-5, 2 * math.pi * 2684.0
    closed = float(viscoelastic.paper_eq25_extra(x, damping_constant=a, omega=w)) / (a * w)
    assert closed == pytest.approx(-(math.sqrt(1 + x) - math.sqrt(1 - x)) / 4, rel=1e-14)
    for n in (4000, 40000):  # N divisible by 4: converges (O(1/N^2)) to the closed form
        assert secant_extra(x, n) == pytest.approx(closed, rel=2e-3 * (4000 / n) ** 2)
    assert secant_extra(x, 4002) == pytest.approx(-closed, rel=1e-3)  # N = 2 mod 4: sign flips
    assert abs(secant_extra(x, 4001)) < 1e-10  # N = 1 mod 4: grid on turning points, correct 0
    assert not np.isfinite(secant_extra(x, 4003))  # N = 3 mod 4: 0/0


def test_secant_artefact_general_offset():
    """Grid t_j = (j + theta) dt, M intervals: the remainder is (1/4)[sqrt(1+x) cot(pi b1)
    + sqrt(1-x) cot(pi b2)], b = 1/2 - (fraction of the interval before the turning point)."""
    x, m = 0.6, 20000
    for theta in (0.1, 0.37):
        dt = 2 * np.pi / m
        t = (np.arange(m + 1) + theta) * dt
        h = np.sqrt(1 + x * np.sin(t)) * x * np.cos(t)
        s = x * np.sin(t)
        num = np.sum(np.diff(h) / np.diff(s)) * dt / (4 * np.pi)
        al1 = ((np.pi / 2) / dt - theta) % 1.0
        al2 = ((3 * np.pi / 2) / dt - theta) % 1.0
        ref = 0.25 * (math.sqrt(1 + x) / math.tan(math.pi * (0.5 - al1))
                      + math.sqrt(1 - x) / math.tan(math.pi * (0.5 - al2)))
        assert num == pytest.approx(ref, rel=1e-3, abs=1e-6)


def test_paper_eq25_curve_and_grey_curve():
    f0, _, _ = hertz_f0(210e9)
    a, w = a_paper(1.05e6, 210e9, NU), 2 * math.pi * f0
    x = jnp.array([0.2, 0.6, 1.0, 1.5])
    full = np.asarray(viscoelastic.shift_paper_eq25(x, damping_constant=a, omega=w))
    hz = np.asarray(viscoelastic.shift_first_order(x))
    extra = -(a * w / 4) * (np.sqrt(1 + np.asarray(x)) - np.sqrt(np.clip(1 - np.asarray(x), 0, None)))
    np.testing.assert_allclose(full, hz + extra, rtol=1e-13)
    assert full[2] == pytest.approx(-0.05 - 0.066, abs=0.004)  # Fig. 4 black dashed at x = 1
    grey = np.asarray(viscoelastic.shift_paper_without_first_order(x, damping_constant=a, omega=w))
    np.testing.assert_allclose(grey, np.sqrt(1 + 2 * full) - 1, rtol=1e-13)
    # x > 1: sqrt(1 - x) clipped, value continuous at 1 and finite beyond
    e = lambda xx: float(viscoelastic.paper_eq25_extra(xx, damping_constant=a, omega=w))
    assert e(1.0 + 1e-12) == pytest.approx(e(1.0), abs=1e-9)
    assert e(1.5) == pytest.approx(-(a * w / 4) * math.sqrt(2.5))


def test_paper_eq25_gradients_finite():
    f = lambda x, a, w: viscoelastic.shift_paper_eq25(x, damping_constant=a, omega=w)
    xs = jnp.array([0.0, 0.5, 1.0 - 1e-9, 1.3, 1.0])
    g = jax.jit(jax.vmap(jax.grad(f, argnums=(0, 1, 2)), in_axes=(0, None, None)))(xs, 1.1e-5, 1.7e4)
    g = np.stack([np.asarray(v) for v in g])
    assert np.all(np.isfinite(g[:, :4])), g
    # at x = 1 exactly the Hertz part's true d/dx is -inf (models.ladder.first_order); never NaN
    assert not np.any(np.isnan(g[:, 4]))
    e = lambda x, a, w: viscoelastic.paper_eq25_extra(x, damping_constant=a, omega=w)
    assert all(np.isfinite(float(v)) for v in jax.grad(e, argnums=(0, 1, 2))(1.0, 1.1e-5, 1.7e4))
    # the true d/dx of sqrt(1 - x) diverges as x -> 1-: large but finite just below 1
    g = jax.grad(lambda x: viscoelastic.paper_eq25_extra(x, damping_constant=1.1e-5, omega=1.7e4))
    assert abs(float(g(1.0 - 1e-10))) > 1e2 * abs(float(g(0.5)))
