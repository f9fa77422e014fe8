"""The Masing hysteresis element (models/laws/masing.py) against references built here:
mpmath and QUADPACK quadratures of the loop, Masing's branches written out independently,
an Iwan element driven through cycles, and a time-integrated forced oscillator."""

import jax
import jax.numpy as jnp
import mpmath as mp
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq, minimize_scalar

from beadrod.models.laws import masing

M_VALUES = (1.1, 1.5, 2.0, 2.5, 2.9)


# --- the loop, written out from the definitions (no code under test) ------------------


def virgin(u, k, a, m):
    return k * u - a * np.abs(u) ** (m - 1) * u


def descending(u, U, k, a, m):
    return virgin(U, k, a, m) - 2 * virgin((U - u) / 2, k, a, m)


def ascending(u, U, k, a, m):
    return -descending(-u, U, k, a, m)


def loop(theta, U, k, a, m):
    u = U * np.cos(theta)
    return descending(u, U, k, a, m) if theta % (2 * np.pi) <= np.pi else ascending(u, U, k, a, m)


QUAD = dict(epsabs=0.0, epsrel=1e-12, limit=200)


def fourier(U, k, a, m, w):
    """Int_0^2pi f(theta) w(theta) d theta over the steady loop, by QUADPACK per branch."""
    return sum(quad(lambda t: loop(t, U, k, a, m) * w(t), lo, hi, **QUAD)[0]
               for lo, hi in ((0.0, np.pi), (np.pi, 2 * np.pi)))


def harmonics(U, k, a, m):
    """(D, dk, q) of the steady loop by QUADPACK: D = loop area, dk the in-phase first
    harmonic less k, q the quadrature one, on u = U cos(theta)."""
    D = quad(lambda u: ascending(u, U, k, a, m) - descending(u, U, k, a, m), -U, U, **QUAD)[0]
    return (D, fourier(U, k, a, m, np.cos) / (np.pi * U) - k,
            -fourier(U, k, a, m, np.sin) / (np.pi * U))


# --- 1-3: closed forms ---------------------------------------------------------------


@pytest.mark.parametrize("m", M_VALUES)
def test_harmonic_integral_matches_mpmath(m):
    mp.mp.dps = 30
    ref = mp.quad(lambda t: (1 - mp.cos(t)) ** m * mp.cos(t), [0, mp.pi])
    assert float(masing.harmonic_integral(m)) == pytest.approx(float(ref), rel=1e-12)
    # the equivalent form -2^(m+1) W(m) m/(m+1), W = (sqrt(pi)/2) Gamma(m+1/2)/Gamma(m+1)
    w = mp.sqrt(mp.pi) / 2 * mp.gamma(m + 0.5) / mp.gamma(m + 1)
    assert float(-(2 ** (m + 1)) * w * m / (m + 1)) == pytest.approx(float(ref), rel=1e-12)


def test_harmonic_integral_rayleigh_case():
    assert float(masing.harmonic_integral(2.0)) == pytest.approx(-np.pi, rel=1e-14)
    assert float(masing.in_phase_change(0.3, a=2.0, m=2.0)) == pytest.approx(-0.6, rel=1e-14)


@pytest.mark.parametrize("a, m, U", [(1.0, 1.1, 0.7), (0.3, 1.5, 2.0), (2.0, 2.0, 0.5),
                                     (0.05, 2.5, 3.0), (1.0, 2.9, 1.0), (4.0, 3.0, 0.2)])
def test_loop_closed_forms_match_quadrature_of_the_branches(a, m, U):
    k = 3.0  # a linear part: the closed forms must leave it out
    D, dk, q = harmonics(U, k, a, m)
    assert float(masing.loop_area(U, a=a, m=m)) == pytest.approx(D, rel=1e-10)
    assert float(masing.in_phase_change(U, a=a, m=m)) == pytest.approx(dk, rel=1e-10)
    assert float(masing.quadrature_stiffness(U, a=a, m=m)) == pytest.approx(q, rel=1e-10)
    assert q == pytest.approx(D / (np.pi * U**2), rel=1e-10)
    # the module's branches are the ones written out above
    u = np.linspace(-U, U, 41)
    top = virgin(U, k, a, m)
    np.testing.assert_allclose(masing.virgin_force(u, k=k, a=a, m=m), virgin(u, k, a, m),
                               rtol=1e-13, atol=1e-14 * abs(top))
    np.testing.assert_allclose(masing.branch_force(u, u_rev=U, f_rev=top, k=k, a=a, m=m),
                               descending(u, U, k, a, m), rtol=1e-13, atol=1e-13 * abs(top))
    np.testing.assert_allclose(masing.branch_force(u, u_rev=-U, f_rev=-top, k=k, a=a, m=m),
                               ascending(u, U, k, a, m), rtol=1e-13, atol=1e-13 * abs(top))
    theta = np.linspace(0.0, 2 * np.pi, 37)
    np.testing.assert_allclose(masing.loop_force(theta, amplitude=U, k=k, a=a, m=m),
                               [loop(t, U, k, a, m) for t in theta], rtol=1e-13,
                               atol=1e-13 * abs(top))
    # Masing's loop closes at both tips
    assert descending(-U, U, k, a, m) == pytest.approx(virgin(-U, k, a, m), rel=1e-13)


def test_loss_to_shift_ratio():
    rho = masing.loss_to_shift_ratio
    assert float(rho(2.0)) == pytest.approx(8 / (3 * np.pi), rel=1e-14)
    for m in M_VALUES:  # the gamma form, by mpmath
        ref = 2 * (m - 1) * mp.gamma(m + 1) / (mp.sqrt(mp.pi) * m * mp.gamma(m + 0.5))
        assert float(rho(m)) == pytest.approx(float(ref), rel=1e-13)
    # -> 0 at m -> 1, linearly with slope 4/pi, and continuous
    for eps in (1e-3, 1e-6, 1e-9):
        eps = (1.0 + eps) - 1.0  # the step float64 holds
        assert float(rho(1 + eps)) / eps == pytest.approx(4 / np.pi, rel=3 * eps)
    assert float(rho(1.0)) == 0.0
    r = np.asarray(rho(np.linspace(1.0, 3.0, 2001)))
    assert np.all(np.diff(r) > 0)
    assert np.max(np.diff(r)) < 1.5e-3  # slope <= 4/pi: no jump
    assert np.max(np.abs(np.diff(r, 2))) < 1e-5
    # rho is the ratio of the added loss to the frequency drop, and twice q/|dk|
    for m in M_VALUES:
        for x in (0.1, 1.0, 2.5):
            dq = float(masing.loss_change(x, strength=0.02, exponent=m))
            df = float(masing.shift_first_order(x, strength=0.02, exponent=m))
            assert dq / abs(df) == pytest.approx(float(rho(m)), rel=1e-13)
        U, a = 0.7, 1.3
        q = float(masing.quadrature_stiffness(U, a=a, m=m))
        dk = float(masing.in_phase_change(U, a=a, m=m))
        assert 2 * q / abs(dk) == pytest.approx(float(rho(m)), rel=1e-13)


@pytest.mark.parametrize("m", (1.0 + 1e-9, *M_VALUES, 3.0))
def test_strength_is_the_frequency_drop_at_the_static_overlap(m):
    k0, delta0, h = 2.5e6, 3e-7, 0.013
    a = masing.coefficient_from_strength(h, m, k0=k0, delta0=delta0)
    assert float(masing.strength_from_coefficient(a, m, k0=k0, delta0=delta0)) == \
        pytest.approx(h, rel=1e-13)
    # -dk(U = delta0)/(2 k0) = h, from the quadrature of the loop (k = 0)
    dk = fourier(delta0, 0.0, float(a), m, np.cos) / (np.pi * delta0)
    assert -dk / (2 * k0) == pytest.approx(h, rel=1e-9)
    for x in (0.2, 1.0, 2.0):
        U = x * delta0
        assert float(masing.stiffness_change(x, strength=h, exponent=m)) == pytest.approx(
            float(masing.in_phase_change(U, a=a, m=m)) / k0, rel=1e-12)
        assert float(masing.loss_change(x, strength=h, exponent=m)) == pytest.approx(
            float(masing.quadrature_stiffness(U, a=a, m=m)) / k0, rel=1e-12)
        assert float(masing.shift_first_order(x, strength=h, exponent=m)) == pytest.approx(
            float(masing.stiffness_change(x, strength=h, exponent=m)) / 2, rel=1e-14)


# --- 4: numerical safety -------------------------------------------------------------


DIMENSIONLESS = (masing.stiffness_change, masing.loss_change, masing.shift_first_order)


def test_zero_strength_gives_exactly_zero():
    x = jnp.array([0.0, 1e-12, 0.5, 1.0, 3.0])
    for m in (1.0 + 1e-9, 1.01, 2.0, 2.99, 3.0):
        for f in DIMENSIONLESS:
            assert np.all(np.asarray(f(x, strength=0.0, exponent=m)) == 0.0)
        assert float(masing.coefficient_from_strength(0.0, m, k0=1e6, delta0=1e-7)) == 0.0
        for f in (masing.loop_area, masing.in_phase_change, masing.quadrature_stiffness):
            assert np.all(np.asarray(f(x, a=0.0, m=m)) == 0.0)
    for f in DIMENSIONLESS:  # and at x = 0 whatever the strength
        assert float(f(0.0, strength=0.05, exponent=1.5)) == 0.0


def test_gradients_are_finite_over_the_prior_region():
    xs = [0.0, 1e-300, 1e-12, 1e-6, 0.1, 1.0, 3.0]
    ms = [1.0 + 1e-9, 1.01, 1.3, 2.0, 2.5, 2.99, 3.0]
    hs = [0.0, 1e-3, 0.05]
    x, m, h = (jnp.asarray(v).ravel() for v in np.meshgrid(xs, ms, hs, indexing="ij"))
    for f in DIMENSIONLESS:
        g = jax.vmap(jax.grad(lambda x, h, m, f=f: f(x, strength=h, exponent=m),
                              argnums=(0, 1, 2)))(x, h, m)
        for gi in g:
            assert np.all(np.isfinite(np.asarray(gi))), f.__name__
        assert np.all(np.isfinite(np.asarray(f(x, strength=h, exponent=m))))
    for f in (masing.loop_area, masing.in_phase_change, masing.quadrature_stiffness):
        g = jax.vmap(jax.grad(lambda U, a, m, f=f: f(U, a=a, m=m), argnums=(0, 1, 2)))(x, h, m)
        assert all(np.all(np.isfinite(np.asarray(gi))) for gi in g), f.__name__

    def conv(h, m):
        a = masing.coefficient_from_strength(h, m, k0=2.0, delta0=0.5)
        return a + masing.strength_from_coefficient(a, m, k0=2.0, delta0=0.5)

    for fun in (conv, lambda h, m: h * masing.loss_to_shift_ratio(m)
                + masing.harmonic_integral(m)):
        g = jax.vmap(jax.grad(fun, argnums=(0, 1)))(h, m)
        assert all(np.all(np.isfinite(np.asarray(gi))) for gi in g)
    # the branches at the origin and at the loop's tips
    u = jnp.array([0.0, 1e-12, -1e-12, 1.0, -1.0])
    g = jax.vmap(jax.grad(lambda u, m: masing.branch_force(u, u_rev=1.0, f_rev=0.3, a=0.2, m=m,
                                                           k=1.0), argnums=(0, 1)))(
        u, jnp.full(u.shape, 1.5))
    assert all(np.all(np.isfinite(np.asarray(gi))) for gi in g)


# --- 5: the Iwan element -------------------------------------------------------------


@jax.jit
def _iwan_cycles(u, stiff, slip):
    def step(z, ui):
        f, z = masing.iwan_force(ui, z, stiff, slip)
        return z, f

    return jax.lax.scan(step, jnp.zeros_like(stiff), u)[1]


def iwan_loop(n, U, a, m, phi_max, steps=4000, cycles=3):
    """(D, dk, q) of an n-slider Iwan element's last loop under u = U cos(theta): D by the
    trapezoidal rule for the closed path integral of f du, dk and q by the rectangle rule
    on the periodic samples."""
    stiff, slip = masing.iwan_element(n, a=a, m=m, phi_max=phi_max)
    theta = 2 * np.pi * np.arange(steps * cycles + 1) / steps
    u = U * np.cos(theta)
    f = np.asarray(_iwan_cycles(jnp.asarray(u), stiff, slip))[-steps - 1:]
    u, t = u[-steps - 1:], theta[-steps - 1:]
    D = np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u))
    mean = lambda g: np.mean(f[:-1] * g(t[:-1])) * 2 * np.pi
    return D, mean(np.cos) / (np.pi * U) - float(np.sum(stiff)), -mean(np.sin) / (np.pi * U)


@pytest.mark.parametrize("m", (1.1, 1.5, 2.0, 2.5, 3.0))
def test_iwan_loop_converges_to_the_closed_forms(m):
    """Measured relative errors (U = 1, phi_max = 1.5 U; a = 1):
    N = 50: D and q <= 4.4e-3 (m = 1.1; <= 1.3e-3 for m >= 1.5), dk <= 4.5e-4;
    N = 200: D and q <= 2.7e-4, dk <= 6.1e-5; they fall about as 1/N^2.
    Asserted: < 1e-2 at N = 50, < 1e-3 at N = 200, and a fall by 4 or more.
    """
    a, U = 1.0, 1.0
    D0 = float(masing.loop_area(U, a=a, m=m))
    dk0 = float(masing.in_phase_change(U, a=a, m=m))
    q0 = float(masing.quadrature_stiffness(U, a=a, m=m))
    errs = {}
    for n in (50, 200):
        D, dk, q = iwan_loop(n, U, a, m, 1.5 * U)
        errs[n] = max(abs(D / D0 - 1), abs(dk / dk0 - 1), abs(q / q0 - 1))
    assert errs[50] < 1e-2
    assert errs[200] < 1e-3
    assert errs[200] < errs[50] / 4


@pytest.mark.parametrize("m", (1.1, 1.5, 2.0, 3.0))
def test_iwan_virgin_curve_and_loop_shape(m):
    """N = 200: virgin curve k_I u - a u^m on [0, phi_max] (exact at the bin edges) and the
    steady loop at U = 0.8 phi_max against Masing's branches. Measured max error / max
    force, virgin and loop: 3.3e-4, 3.7e-4 (m = 1.1); 1.9e-5, 3.3e-5 (1.5); 6.2e-6, 1.3e-5
    (2); 5.2e-5, 1.1e-4 (3). Asserted: < 5e-4."""
    a, phi_max, n = 0.7, 2.0, 200
    stiff, slip = masing.iwan_element(n, a=a, m=m, phi_max=phi_max)
    k_i = float(np.sum(stiff))
    assert k_i == pytest.approx(a * m * phi_max ** (m - 1), rel=1e-13)
    # k_total gives the same element
    s2, p2 = masing.iwan_element(n, a=a, m=m, k_total=k_i)
    np.testing.assert_allclose(p2, slip, rtol=1e-12)
    np.testing.assert_allclose(s2, stiff, rtol=1e-13)
    u = np.linspace(0.0, phi_max, 2001)
    f, _ = masing.iwan_force(u, jnp.zeros((u.size, n)), stiff, slip)
    ref = virgin(u, k_i, a, m)
    assert np.max(np.abs(np.asarray(f) - ref)) < 5e-4 * np.max(ref)
    # at the bin edges phi_j = phi_max (j/n)^(1/(m-1)) the force is exact
    edges = phi_max * (np.arange(1, n + 1) / n) ** (1 / (m - 1))
    f, _ = masing.iwan_force(edges, jnp.zeros((n, n)), stiff, slip)
    np.testing.assert_allclose(f, virgin(edges, k_i, a, m), rtol=1e-11, atol=1e-14)
    # beyond phi_max every slider slips: the force stays at a (m - 1) phi_max^m
    f, _ = masing.iwan_force(3.0 * phi_max, jnp.zeros(n), stiff, slip)
    assert float(f) == pytest.approx(a * (m - 1) * phi_max**m, rel=1e-12)
    # the steady loop at U = 0.8 phi_max follows Masing's branches
    U, steps = 0.8 * phi_max, 2000
    theta = 2 * np.pi * np.arange(2 * steps + 1) / steps
    f = np.asarray(_iwan_cycles(jnp.asarray(U * np.cos(theta)), stiff, slip))[-steps:]
    ref = np.array([loop(t, U, k_i, a, m) for t in theta[-steps:]])
    assert np.max(np.abs(f - ref)) < 5e-4 * np.max(np.abs(ref))


# --- 6: forced oscillator against the describing function -----------------------------


def df_parts(U, a, m):
    return (float(masing.in_phase_change(U, a=a, m=m)),
            float(masing.quadrature_stiffness(U, a=a, m=m)))


def df_amplitude(w, F, a, m, c, u_max):
    """First-harmonic balance of u'' + c u' + u + (element) = F cos(w t): amplitude U."""
    def g(U):
        dk, q = df_parts(U, a, m)
        return U * np.hypot(1 + dk - w * w, q + c * w) - F
    return brentq(g, 1e-9, u_max, xtol=1e-15, rtol=1e-14)


def df_peak(F, a, m, c, u_max):
    """(w, U) of the describing function's resonance peak: dU/dw = 0 where the residual
    (1 + dk - w^2)^2 + (q + c w)^2 is least over w at fixed U, and U times its root is F."""
    def least(U):
        dk, q = df_parts(U, a, m)
        r = minimize_scalar(lambda w: (1 + dk - w * w) ** 2 + (q + c * w) ** 2,
                            bounds=(0.8, 1.1), method="bounded", options={"xatol": 1e-13})
        return r.x, U * np.sqrt(r.fun)
    U = brentq(lambda U: least(U)[1] - F, 1e-6, u_max, xtol=1e-15, rtol=1e-14)
    return least(U)[0], U


@jax.jit
def _forced_amplitude(stiff, slip, k_lin, c, F, w, U, psi):
    """First-harmonic amplitude of u'' + c u' + k_lin u + F_I(u) = F cos(w t) after
    CYCLES periods of STEPS steps (velocity Verlet, the damping implicit), vmapped over
    w; started on the describing function's orbit u = U cos(w t - psi) with the sliders'
    states on its loop (virgin to U, down to -U, up to U cos psi: monotone moves, exact)."""
    def one(w, U, psi):
        dt = 2 * jnp.pi / w / STEPS
        z = jnp.zeros_like(stiff)
        _, z = masing.iwan_force(U, z, stiff, slip)
        _, z = masing.iwan_force(-U, z, stiff, slip)
        u0 = U * jnp.cos(psi)
        f0, z = masing.iwan_force(u0, z, stiff, slip)
        v0 = U * w * jnp.sin(psi)

        def step(carry, i):
            u, v, acc, z = carry
            u1 = u + dt * v + 0.5 * dt * dt * acc
            f1, z1 = masing.iwan_force(u1, z, stiff, slip)
            r1 = F * jnp.cos(w * (i + 1) * dt) - k_lin * u1 - f1
            v1 = (v + 0.5 * dt * (acc + r1)) / (1 + 0.5 * c * dt)
            return (u1, v1, r1 - c * v1, z1), u1

        start = (u0, v0, F - c * v0 - k_lin * u0 - f0, z)
        us = jax.lax.scan(step, start, jnp.arange(STEPS * CYCLES))[1][-STEPS:]
        t = (jnp.arange(STEPS * (CYCLES - 1), STEPS * CYCLES) + 1) * dt
        return 2 * jnp.hypot(jnp.mean(us * jnp.cos(w * t)), jnp.mean(us * jnp.sin(w * t)))

    return jax.vmap(one)(w, U, psi)


STEPS, CYCLES, SLIDERS, POINTS, SPAN = 1000, 50, 200, 7, 0.2


def peak_of(w, U, w_ref):
    """Vertex of a quartic through the points (w, U)."""
    p = np.polyfit(w - w_ref, U, 4)
    r = minimize_scalar(lambda d: -np.polyval(p, d), bounds=(w[0] - w_ref, w[-1] - w_ref),
                        method="bounded", options={"xatol": 1e-14})
    return w_ref + r.x, -r.fun


@pytest.mark.parametrize("m, x", [(2.0, 0.5), (2.0, 1.0), (2.0, 3.0), (1.5, 4.0)])
def test_forced_resonance_matches_the_describing_function(m, x):
    """u'' + c u' + u + (Masing element, h = 0.01, as an N = 200 Iwan element in parallel
    with k - k_I) = F cos(w t), c = 0.01, F set for a peak amplitude near x (delta0 = 1):
    frequency drops 0.5 % (m = 2, x = 0.5), 1 %, 3 % (m = 2, x = 3), 2 % (m = 1.5, x = 4).
    Seven frequencies within +-0.2 half-bandwidths of the describing function's exact peak,
    each started on its describing-function orbit (the transient starts at the size of the
    describing function's error) and run 50 periods, 2.2 to 5.6 envelope decay times
    2/(q + c w); 1000 Verlet steps a period (frequency error (w dt)^2/24 = 1.6e-6). Peak =
    vertex of a quartic through the seven amplitudes (its bias on the describing
    function's own curve: at most 1.5e-4 of the shift, 4e-7 of the amplitude).

    Measured, time integration against the describing function's exact peak (relative;
    x = 0.5, 1, 3 at m = 2, then x = 4 at m = 1.5): shift 1 - w_peak -4.0e-4, -2.9e-4,
    -3.6e-4, -1.6e-4 (halving dt: -2.0e-4, -1.1e-4, -2.5e-4, -0.9e-4, the rest of the
    difference is Verlet's); peak amplitude 3.0e-5, 1.4e-5, -4.2e-5, -6.6e-5; first-harmonic
    amplitude at each frequency <= 2.6e-4. Asserted: shift within 2e-3, peak amplitude
    within 5e-4, each amplitude within 1e-3. For contrast, w_peak^2 = 1 + dk(U_peak)
    misses the shift by -7.1e-3, -4.6e-3, -3.1e-3, -2.5e-3: the exact peak has
    1 + dk - w^2 = c (q + c w)/(2 w), an O(1/Q^2) term.
    """
    h, c = 0.01, 0.01
    a = float(masing.coefficient_from_strength(h, m, k0=1.0, delta0=1.0))
    dk, q = df_parts(x, a, m)
    F = x * (q + c)
    u_max = 3 * x
    w_p, U_p = df_peak(F, a, m, c, u_max)
    stiff, slip = masing.iwan_element(SLIDERS, a=a, m=m, phi_max=1.5 * u_max)
    k_lin = 1.0 - float(np.sum(stiff))
    half_band = (q + c) / 2
    w = w_p + SPAN * half_band * np.linspace(-1, 1, POINTS)
    U = np.array([df_amplitude(wi, F, a, m, c, u_max) for wi in w])
    parts = [df_parts(Ui, a, m) for Ui in U]
    psi = np.array([np.arctan2(qi + c * wi, 1 + dki - wi * wi)
                    for (dki, qi), wi in zip(parts, w)])
    U_ti = np.asarray(_forced_amplitude(stiff, slip, k_lin, c, F, jnp.asarray(w),
                                        jnp.asarray(U), jnp.asarray(psi)))
    w_ti, U_ti_peak = peak_of(w, U_ti, w_p)
    assert 0.004 < 1 - w_p < 0.035  # the regime the brief asks for
    assert (1 - w_ti) / (1 - w_p) - 1 == pytest.approx(0.0, abs=2e-3)
    assert U_ti_peak / U_p - 1 == pytest.approx(0.0, abs=5e-4)
    np.testing.assert_allclose(U_ti, U, rtol=1e-3)
