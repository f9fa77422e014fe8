"""Longitudinal waves in the rod: bar velocity, Rayleigh-Love correction, Pochhammer-Chree.

The rod (radius a = diameter/2, paper Sec. 3) carries the drive to the bead. Three
levels of description, cheapest first:

* bar (1-D) wave: c0 = (E/rho)^(1/2), dispersionless;
* Rayleigh-Love lateral-inertia correction (Rayleigh, *Theory of Sound* Sec. 157;
  Love, *Treatise* Sec. 278; Graff, *Wave Motion in Elastic Solids*, Sec. 8.1):
  v_phase = c0 [1 - nu^2 pi^2 (a/Lambda)^2] = c0 [1 - nu^2 (k a)^2 / 4] with a the
  **radius**; then omega = c0 k (1 - nu^2 k^2 a^2/4) gives
  v_group = d omega/dk = c0 [1 - 3 nu^2 (k a)^2 / 4].
  The paper's Eq. 2, c0[1 - nu (k a_r/2)^2] with a_r = 12 mm the *diameter*, has nu
  where the expansion of the Pochhammer-Chree equation gives nu^2/4: it overstates
  the (tiny) correction by 4/nu = 14.8x. The tests confirm nu^2/4 against an
  independent scipy solution of the exact equation.
* the first longitudinal Pochhammer-Chree branch (paper Eq. 1, a = radius):
  (2p/a)(q^2+k^2) J1(pa) J1(qa) - (q^2-k^2)^2 J0(pa) J1(qa) - 4k^2 p q J1(pa) J0(qa) = 0,
  p^2 = omega^2/V_L^2 - k^2, q^2 = omega^2/V_T^2 - k^2.

Real continuation. Divided by q, every term is an entire function of p^2 and q^2:
J0(pa) = E0(p^2 a^2), J1(pa)/p = (a/2) E1(p^2 a^2), p J1(pa) = (p^2 a/2) E1(p^2 a^2), with
E0(s) = sum (-s/4)^m/(m!)^2, E1(s) = sum (-s/4)^m/(m!(m+1)!). For p^2 < 0 these series
are I0(|p|a) and 2 I1(|p|a)/(|p|a) (J_n(i z) = i^n I_n(z)), so no complex arithmetic,
no branch, and the residual is a polynomial-smooth real function through p^2 = 0 and
q^2 = 0. With Omega = omega a/V_T, beta = (V_T/c)^2 (c the phase velocity),
kappa^2 = (V_T/V_L)^2 = (1-2nu)/(2(1-nu)) the residual divided by 2 a^3 q / Omega^4 is

    D(Omega, beta) = (kappa^2 - beta) E1(P) E1(Qt) - (1 - 2 beta)^2 E0(P) E1(Qt)
                     - 4 beta (kappa^2 - beta) E1(P) E0(Qt),
    P = (kappa^2 - beta) Omega^2,  Qt = (1 - beta) Omega^2,

whose Omega -> 0 limit kappa^2 - 1 + beta (3 - 4 kappa^2) = 0 gives c = c0 exactly.
Domain: Omega < 3 (below the cut-off of the second longitudinal branch, Omega ~ 3.8 for
steel, so the first branch is the only real root in beta and bisection cannot jump
branches; f < 3 V_T/(2 pi a) ~ 250 kHz for the paper's rod). The series use 40 terms:
relative accuracy better than 1e-12 for |s| < 100.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.scene.materials import wave_speeds

__all__ = [
    "bar_velocity",
    "rayleigh_velocity",
    "rayleigh_group_velocity",
    "paper_eq2_velocity",
    "pochhammer_chree_residual",
    "first_branch_beta",
    "first_branch_wavenumber",
    "first_branch_phase_velocity",
    "first_branch_group_velocity",
    "first_resonance_free_free",
    "first_resonance_fixed_free",
    "OMEGA_MAX",
]

OMEGA_MAX = 3.0
"""Largest dimensionless frequency omega a / V_T where the first-branch solver is valid."""

_NTERMS = 40
# Horner coefficients, highest power first (a rolled loop keeps the traced graph small)
_C0 = np.array([1.0 / math.factorial(m) ** 2 for m in range(_NTERMS)][::-1])
_C1 = np.array([1.0 / (math.factorial(m) * math.factorial(m + 1))
                for m in range(_NTERMS)][::-1])


def _series(s: jnp.ndarray, coeffs: np.ndarray) -> jnp.ndarray:
    u = -0.25 * s
    c = jnp.asarray(coeffs, dtype=u.dtype)
    return jax.lax.fori_loop(1, len(coeffs), lambda i, acc: acc * u + c[i],
                             jnp.zeros_like(u) + c[0])


def _e0(s: ArrayLike) -> jnp.ndarray:
    """E0(s) = J0(sqrt(s)) for s >= 0, I0(sqrt(-s)) for s < 0 (entire in s)."""
    return _series(jnp.asarray(s, dtype=float), _C0)


def _e1(s: ArrayLike) -> jnp.ndarray:
    """E1(s) = 2 J1(z)/z with z = sqrt(s); 2 I1(z)/z with z = sqrt(-s) for s < 0."""
    return _series(jnp.asarray(s, dtype=float), _C1)


def bar_velocity(young: ArrayLike, density: ArrayLike) -> jnp.ndarray:
    """c0 = (E/rho)^(1/2) [m/s], the dispersionless bar velocity."""
    return jnp.sqrt(jnp.asarray(young) / density)


def _bar_ka(frequency, young, density, radius):
    return 2.0 * jnp.pi * frequency / bar_velocity(young, density) * radius


def rayleigh_velocity(frequency: ArrayLike, *, young: ArrayLike, poisson: ArrayLike,
                      density: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """Rayleigh-Love phase velocity c0 [1 - nu^2 (k a)^2 / 4] [m/s]; a = rod radius [m].

    k = 2 pi f / c0 (the bar wavenumber; the difference is of higher order).
    """
    ka = _bar_ka(frequency, young, density, radius)
    return bar_velocity(young, density) * (1.0 - jnp.square(poisson * ka) / 4.0)


def rayleigh_group_velocity(frequency: ArrayLike, *, young: ArrayLike, poisson: ArrayLike,
                            density: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """Rayleigh-Love group velocity c0 [1 - 3 nu^2 (k a)^2 / 4] [m/s]; a = rod radius [m]."""
    ka = _bar_ka(frequency, young, density, radius)
    return bar_velocity(young, density) * (1.0 - 0.75 * jnp.square(poisson * ka))


def paper_eq2_velocity(frequency: ArrayLike, *, young: ArrayLike, poisson: ArrayLike,
                       density: ArrayLike, diameter: ArrayLike) -> jnp.ndarray:
    """The paper's Eq. 2 as printed: c0 [1 - nu (k a_r / 2)^2], a_r the diameter [m].

    Kept only to reproduce the paper; the correct coefficient is nu^2/4 on (k a)^2 with
    a the radius (:func:`rayleigh_velocity`).
    """
    k = 2.0 * jnp.pi * frequency / bar_velocity(young, density)
    return bar_velocity(young, density) * (1.0 - poisson * jnp.square(k * diameter / 2.0))


def _kappa2(poisson):
    return (1.0 - 2.0 * poisson) / (2.0 * (1.0 - poisson))


def _d(omega_t, beta, kappa2):
    w2 = jnp.square(omega_t)
    p = (kappa2 - beta) * w2
    qt = (1.0 - beta) * w2
    e0p, e1p, e0q, e1q = _e0(p), _e1(p), _e0(qt), _e1(qt)
    return ((kappa2 - beta) * e1p * e1q - jnp.square(1.0 - 2.0 * beta) * e0p * e1q
            - 4.0 * beta * (kappa2 - beta) * e1p * e0q)


@jax.jit
def pochhammer_chree_residual(wavenumber: ArrayLike, frequency: ArrayLike, *, young: ArrayLike,
                              poisson: ArrayLike, density: ArrayLike,
                              radius: ArrayLike) -> jnp.ndarray:
    """Paper Eq. 1 divided by q, in its real continuation [m^-5 after the division].

    Returns (2p/a)(q^2+k^2) J1(pa) J1(qa)/q - (q^2-k^2)^2 J0(pa) J1(qa)/q
    - 4k^2 p J1(pa) J0(qa), evaluated through the entire series (module docstring), so
    it is real and smooth for either sign of p^2 and q^2. k [rad/m], f [Hz], a radius [m].
    """
    vl, vt, _ = wave_speeds(young, poisson, density)
    k = jnp.asarray(wavenumber, dtype=float)
    w = 2.0 * jnp.pi * jnp.asarray(frequency, dtype=float)
    a = jnp.asarray(radius, dtype=float)
    p2 = jnp.square(w / vl) - k**2
    q2 = jnp.square(w / vt) - k**2
    pj1 = p2 * a / 2.0 * _e1(p2 * a**2)          # p J1(pa)
    j1q_over_q = a / 2.0 * _e1(q2 * a**2)         # J1(qa)/q
    return (2.0 / a * (q2 + k**2) * pj1 * j1q_over_q
            - jnp.square(q2 - k**2) * _e0(p2 * a**2) * j1q_over_q
            - 4.0 * k**2 * pj1 * _e0(q2 * a**2))


@jax.jit
def _solve_beta(omega_t, kappa2):
    # Bracket: c/c0 in [0.3, 1.5] contains the first branch (c_R/c0 ~ 0.58 for steel);
    # below the second cut-off it is the only root, so the sign change is unique.
    # c0^2/V_T^2 = 2(1+nu) = (3 - 4 kappa^2)/(1 - kappa^2)
    c0_over_vt2 = (3.0 - 4.0 * kappa2) / (1.0 - kappa2)
    lo = jnp.zeros_like(omega_t) + 1.0 / (1.5**2 * c0_over_vt2)   # c = 1.5 c0
    hi = jnp.zeros_like(omega_t) + 1.0 / (0.3**2 * c0_over_vt2)   # c = 0.3 c0
    f_lo = _d(omega_t, lo, kappa2)

    def bisect(_, state):
        lo, hi, f_lo = state
        mid = 0.5 * (lo + hi)
        f_mid = _d(omega_t, mid, kappa2)
        same = jnp.sign(f_mid) == jnp.sign(f_lo)
        return (jnp.where(same, mid, lo), jnp.where(same, hi, mid),
                jnp.where(same, f_mid, f_lo))

    lo, hi, _ = jax.lax.fori_loop(0, 48, bisect, (lo, hi, f_lo))
    beta = 0.5 * (lo + hi)
    for _ in range(2):  # Newton polish of the bisection midpoint (elementwise D)
        val, slope = jax.jvp(lambda b: _d(omega_t, b, kappa2), (beta,), (jnp.ones_like(beta),))
        beta = beta - val / slope
    return beta


@jax.custom_jvp
def _beta_scalarwise(omega_t, kappa2):
    return _solve_beta(omega_t, kappa2)


@_beta_scalarwise.defjvp
def _beta_jvp(primals, tangents):
    # Implicit function theorem on D(Omega, beta, kappa^2) = 0.
    omega_t, kappa2 = primals
    d_om, d_k2 = tangents
    beta = _beta_scalarwise(omega_t, kappa2)
    _, d_num = jax.jvp(lambda o, k: _d(o, beta, k), (omega_t, kappa2), (d_om, d_k2))
    _, d_b = jax.jvp(lambda b: _d(omega_t, b, kappa2), (beta,), (jnp.ones_like(beta),))
    return beta, -d_num / d_b


def first_branch_beta(omega_t: ArrayLike, poisson: ArrayLike) -> jnp.ndarray:
    """beta = (V_T/c)^2 [-] on the first branch at Omega = omega a / V_T (< OMEGA_MAX).

    Bisection (48 steps) then Newton; gradients by the implicit function theorem.
    """
    omega_t, kappa2 = jnp.broadcast_arrays(jnp.asarray(omega_t, dtype=float),
                                           _kappa2(jnp.asarray(poisson, dtype=float)))
    return _beta_scalarwise(omega_t, kappa2)


def _omega_t(frequency, young, poisson, density, radius):
    _, vt, _ = wave_speeds(young, poisson, density)
    return 2.0 * jnp.pi * jnp.asarray(frequency, dtype=float) * radius / vt, vt


@jax.jit
def first_branch_phase_velocity(frequency: ArrayLike, *, young: ArrayLike, poisson: ArrayLike,
                                density: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """Phase velocity omega/k [m/s] of the first longitudinal Pochhammer-Chree branch.

    f [Hz] (> 0, below ``OMEGA_MAX V_T/(2 pi a)``), a = rod radius [m]. f = 0 returns c0.
    """
    om, vt = _omega_t(frequency, young, poisson, density, radius)
    safe = jnp.where(om > 0, om, 1e-6)
    return vt / jnp.sqrt(first_branch_beta(safe, poisson))


def first_branch_wavenumber(frequency: ArrayLike, *, young: ArrayLike, poisson: ArrayLike,
                            density: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """k(omega) [rad/m] on the first branch."""
    c = first_branch_phase_velocity(frequency, young=young, poisson=poisson, density=density,
                                    radius=radius)
    return 2.0 * jnp.pi * jnp.asarray(frequency) / c


@jax.jit
def first_branch_group_velocity(frequency: ArrayLike, *, young: ArrayLike, poisson: ArrayLike,
                                density: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """Group velocity d omega/dk [m/s] of the first branch, by implicit differentiation.

    With xi = k a = sqrt(beta) Omega: d xi/d Omega = sqrt(beta) + Omega beta'/(2 sqrt(beta)),
    beta' = -D_Omega/D_beta, and v_g = V_T / (d xi/d Omega).
    """
    om, vt = _omega_t(frequency, young, poisson, density, radius)
    om = jnp.where(om > 0, om, 1e-6)
    om, kappa2 = jnp.broadcast_arrays(om, _kappa2(jnp.asarray(poisson, dtype=float)))
    beta = _beta_scalarwise(om, kappa2)
    _, d_om = jax.jvp(lambda o: _d(o, beta, kappa2), (om,), (jnp.ones_like(om),))
    _, d_b = jax.jvp(lambda b: _d(om, b, kappa2), (beta,), (jnp.ones_like(beta),))
    dbeta = -d_om / d_b
    sb = jnp.sqrt(beta)
    return vt / (sb + om * dbeta / (2.0 * sb))


def first_resonance_free_free(length: ArrayLike, *, young: ArrayLike,
                              density: ArrayLike) -> jnp.ndarray:
    """f1 = c0 / (2 L) [Hz] of a free-free bar of length L [m] (no dispersion)."""
    return bar_velocity(young, density) / (2.0 * jnp.asarray(length))


def first_resonance_fixed_free(length: ArrayLike, *, young: ArrayLike,
                               density: ArrayLike) -> jnp.ndarray:
    """f1 = c0 / (4 L) [Hz] of a fixed-free (clamped-free) bar of length L [m]."""
    return bar_velocity(young, density) / (4.0 * jnp.asarray(length))
