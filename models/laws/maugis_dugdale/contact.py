"""Maugis-Dugdale adhesive contact of a sphere on a plane: the JKR-DMT transition.

D. Maugis, J. Colloid Interface Sci. 150, 243 (1992); K. L. Johnson & J. A. Greenwood,
J. Colloid Interface Sci. 192, 326 (1997). A Dugdale cohesive stress sigma0 [Pa] acts
in the annulus a < r < c where the gap is below h0 = w/sigma0 [m]; w = 2 gamma [J/m^2]
is the work of adhesion of two identical surfaces of energy gamma (as models.laws.jkr, dmt).

Maugis' reduced variables, K = 4 E*/3 (E* [Pa] as in models.laws.hertz, 1/E* = 2 (1-nu^2)/E):

    A = a / a_s,  a_s = (pi w R^2/K)^(1/3) [m];   Delta = delta / d_s,  d_s = a_s^2/R [m];
    Pbar = F / F_s,  F_s = pi w R [N];   m = c/a >= 1;
    lam = 2 sigma0 (R/(pi w K^2))^(1/3) = sigma0 (9 R/(2 pi w E*^2))^(1/3)   [-]

(the two forms of lam are the same number; 2 sigma0 (R/(pi w E*^2))^(1/3), with E* in
place of K, would be (16/9)^(1/3) = 1.211 times larger and is not used). With the
Lennard-Jones peak stress sigma0 = 16 w/(9 sqrt(3) z0), lam = 1.1570 mu_T, Tabor's
mu_T = (R w^2/(E*^2 z0^3))^(1/3) (:func:`lennard_jones_parameter`). The state at contact
radius A (Maugis 1992; m from the first equation):

    (lam A^2/2)[(m^2-2) arcsec m + sqrt(m^2-1)] + (4 lam^2 A/3)[sqrt(m^2-1) arcsec m - m + 1] = 1
    Pbar  = A^3 - lam A^2 [sqrt(m^2-1) + m^2 arcsec m]
    Delta = A^2 - (4/3) lam A sqrt(m^2-1)

Numerics. With theta = arcsec m in [0, pi/2] and cbar = c/a_s = A m, the first equation
is a quadratic in cbar with the cancellation-free root

    cbar = 2/(q + (q^2 + 2 lam b1)^(1/2)),  q = (4/3) lam^2 b2,
    b1 = (sin 2theta)/2 - theta cos 2theta,  b2 = theta sin theta - 2 sin^2(theta/2),
    A = cbar cos theta,  Pbar = A^3 - lam cbar^2 (sin theta cos theta + theta),
    Delta = A^2 - (4/3) lam cbar sin theta,

finite for every theta in [0, pi/2] (m -> 1 is theta -> 0, the JKR end; a -> 0 is
theta -> pi/2). theta decreases monotonically as A, delta or F grows on the branches
used, so every inverse (A, Delta or Pbar -> theta) is one scalar root, found by a
bracketed Newton iteration in log theta and differentiated by the implicit function
theorem (custom_jvp), never through the iterations.

Branches, as in models.laws.jkr. The overlap delta -> state is taken on the branch that is
stable under displacement control, d(Delta)/d(theta) < 0, which ends at theta_e(lam):
the minimum of Delta (an interior one for lam > 0.938, where K -> -inf as in JKR), or
a = 0 (theta = pi/2) for lam < 0.938, where the contact branch meets a finite force
(about -2 pi w R as lam -> 0). Below delta_e the bead is taken as separated: force and
stiffness are 0 (the non-contact Dugdale state with a = 0, Maugis 1992, is not modelled,
like the outer attraction in models.laws.dmt, whose snap at delta = 0 this reproduces as
lam -> 0). The load -> state is taken on the load-controlled branch, up to the pull-off
Pbar_c(lam) = min Pbar (-2 as lam -> 0, -3/2 as lam -> inf).

Region (finite values and gradients, tested): lam in [0.01, 200], gamma in [0.05, 5]
J/m^2, E* of E in [150, 250] GPa, R of the 7.938 mm bead, delta from below delta_e to
10^3 delta_0. theta is floored at 1e-7 (overlaps >~ 1e18 d_s: no load reaches it).

The law object with its fast paths is :mod:`models.laws.maugis_dugdale`, built from this
module; the tables and the parametric force (:mod:`models.laws.maugis_dugdale.static`,
:mod:`models.laws.maugis_dugdale.orbit`) import this one, not the law, so no import runs in a
circle.
"""

from __future__ import annotations

import math
from functools import partial

import jax
import jax.numpy as jnp
from jax.typing import ArrayLike

from beadrod.models.ladder.first_order import first_order_from_stiffness
from beadrod.models.safe_math import safe_sqrt

__all__ = [
    "LAM_STAR", "work_of_adhesion", "scales", "transition_parameter", "cohesive_stress",
    "lennard_jones_parameter", "angle_state", "reduced_slope", "end_angle", "pull_off_angle",
    "angle_from_contact_radius", "angle_from_overlap", "angle_from_load", "reduced_pull_off",
    "reduced_end_overlap", "reduced_force", "reduced_stiffness", "pull_off_force",
    "minimum_overlap", "contact_radius", "contact_state", "contact_radius_from_overlap", "force",
    "stiffness", "static_overlap", "linear_stiffness", "linear_frequency", "shift_first_order",
    "modulus_from_frequency", "overlap_from_frequency",
]

LAM_STAR = 0.93795
"""lam below which the displacement-controlled branch ends at a = 0 (Maugis 1992: 0.938)."""

_TH_LO = 1e-7
_TH_TOP = 0.5 * math.pi - 1e-6  # a -> 0 end, kept off pi/2 where theta-slopes are 0/0
_STEPS = 60  # bracketed Newton: ~10 steps from the bracket's middle; 60 is a wide margin
_SLOPE_FLOOR = 1e-12  # |d/dtheta| floor: finite (not infinite) gradients at the branch end
_SERIES_TH = 0.25
# sin u - u cos u = sum_k (-1)^(k+1) 2k u^(2k+1)/(2k+1)!, k = 1..8 (error < 1e-17 relative
# for u < 1/2): the direct form cancels like 1/theta^2 at the JKR end
_B1_COEFFS = tuple((-1.0) ** (k + 1) * 2 * k / math.factorial(2 * k + 1) for k in range(1, 9))


def work_of_adhesion(gamma: ArrayLike) -> jnp.ndarray:
    """w = 2 gamma [J/m^2] (identical surfaces of energy gamma)."""
    return 2.0 * jnp.asarray(gamma)


def scales(*, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike):
    """(a_s [m], d_s [m], F_s [N]) = ((pi w R^2/K)^(1/3), a_s^2/R, pi w R), K = 4 E*/3."""
    fs = jnp.pi * work_of_adhesion(gamma) * radius
    a_s = jnp.cbrt(fs * radius / (4.0 * e_star / 3.0))
    return a_s, a_s**2 / radius, fs


def transition_parameter(*, sigma0: ArrayLike, e_star: ArrayLike, radius: ArrayLike,
                         gamma: ArrayLike) -> jnp.ndarray:
    """lam = sigma0 (9 R/(2 pi w E*^2))^(1/3) [-], sigma0 [Pa] (Maugis 1992)."""
    return sigma0 * jnp.cbrt(9.0 * radius / (2.0 * jnp.pi * work_of_adhesion(gamma) * e_star**2))


def cohesive_stress(*, lam: ArrayLike, e_star: ArrayLike, radius: ArrayLike,
                    gamma: ArrayLike) -> jnp.ndarray:
    """sigma0 [Pa] for a given lam (inverse of :func:`transition_parameter`); h0 = w/sigma0."""
    return lam / transition_parameter(sigma0=1.0, e_star=e_star, radius=radius, gamma=gamma)


def lennard_jones_parameter(*, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike,
                            z0: ArrayLike) -> jnp.ndarray:
    """lam with sigma0 = 16 w/(9 sqrt(3) z0), the Lennard-Jones peak stress [-]; z0 [m].

    Equals 1.1570 mu_T, mu_T = (R w^2/(E*^2 z0^3))^(1/3) (Tabor, with w = 2 gamma), i.e.
    0.5409 x models.laws.adhesion_map.muller_parameter (which the paper evaluates with gamma).
    """
    s0 = 16.0 * work_of_adhesion(gamma) / (9.0 * math.sqrt(3.0) * z0)
    return transition_parameter(sigma0=s0, e_star=e_star, radius=radius, gamma=gamma)


# --- reduced (dimensionless) state, parametric in theta = arcsec m --------------------------

def _b1(th):
    small = th < _SERIES_TH
    u = 2.0 * jnp.where(small, th, 0.0)
    series = jnp.zeros_like(u)
    for c in reversed(_B1_COEFFS):
        series = series * u * u + c
    series = 0.5 * series * u**3
    ul = 2.0 * th
    return jnp.where(small, series, 0.5 * (jnp.sin(ul) - ul * jnp.cos(ul)))


def _cbar(th, lam):
    q = (4.0 / 3.0) * lam**2 * (th * jnp.sin(th) - 2.0 * jnp.sin(0.5 * th) ** 2)
    return 2.0 / (q + jnp.sqrt(q * q + 2.0 * lam * _b1(th)))


def angle_state(theta: ArrayLike, lam: ArrayLike):
    """(A, Pbar, Delta) [-] at theta = arcsec(c/a) in (0, pi/2] (module docstring)."""
    th = jnp.asarray(theta, dtype=float)
    cb = _cbar(th, lam)
    a = cb * jnp.cos(th)
    pbar = a**3 - lam * cb**2 * (jnp.sin(th) * jnp.cos(th) + th)
    return a, pbar, a**2 - (4.0 / 3.0) * lam * cb * jnp.sin(th)


def _radius(th, lam):
    return angle_state(th, lam)[0]


def _load(th, lam):
    return angle_state(th, lam)[1]


def _delta(th, lam):
    return angle_state(th, lam)[2]


def _d_theta(fn, th, lam):
    return jax.jvp(lambda t: fn(t, lam), (th,), (jnp.ones_like(th),))[1]


def _per_area(fn, th, lam):
    # d fn/d(A^2): every theta-slope vanishes like (pi/2 - theta) at a -> 0 (the state is
    # even in A there), so d/dtheta would give a spurious root at pi/2; d/d(A^2) does not
    a, da = jax.jvp(lambda t: _radius(t, lam), (th,), (jnp.ones_like(th),))
    return _d_theta(fn, th, lam) / (2.0 * a * da)


_delta_per_area = partial(_per_area, _delta)  # hashable: a static argument of the solver
_load_per_area = partial(_per_area, _load)


def reduced_slope(theta: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """dPbar/dDelta = (dPbar/dtheta)/(dDelta/dtheta) [-] at theta (K = (F_s/d_s) x this).

    At the interior end of the branch (lam > 0.938) dDelta/dtheta -> 0 and K -> -inf: the
    denominator is floored, returning a large negative finite number instead.
    """
    th = jnp.asarray(theta, dtype=float)
    den = _d_theta(_delta, th, lam)
    den = jnp.where(jnp.abs(den) > _SLOPE_FLOOR, den, -_SLOPE_FLOOR)
    return _d_theta(_load, th, lam) / den


# --- scalar roots in theta with implicit-function derivatives -------------------------------

def _solve(fn, y, lam, hi):
    y, lam, hi = jnp.broadcast_arrays(*(jnp.asarray(v, dtype=float) for v in (y, lam, hi)))
    return _root(fn, y, lam, hi)


@partial(jax.custom_jvp, nondiff_argnums=(0,))
def _root(fn, y, lam, hi):
    """theta in [1e-7, hi] with fn(theta, lam) = y, fn decreasing; clamped to the ends."""
    return _newton(fn, y, lam, hi)


@partial(jax.jit, static_argnums=(0,))
def _newton(fn, y, lam, hi):
    # asinh compresses fn's power-law growth (Delta ~ theta^-3..-4 at the JKR end), so
    # Newton in log theta is nearly linear over the whole range
    def g(u):
        return jnp.arcsinh(fn(jnp.exp(u), lam)) - jnp.arcsinh(y)

    lo = jnp.full_like(y, math.log(_TH_LO))
    up = jnp.log(hi)

    def step(_, s):
        u, a, b, last = s
        f, fp = jax.jvp(g, (u,), (jnp.ones_like(u),))
        a = jnp.where(f > 0, u, a)
        b = jnp.where(f > 0, b, u)
        dx = -f / jnp.where(fp < 0, fp, -1.0)
        # Newton only while it lands in the bracket and at least halves the step
        # (rtsafe, Numerical Recipes Sec. 9.4); bisection otherwise, so 60 steps always
        # resolve the ~16 e-folds of the bracket
        ok = (fp < 0) & (u + dx >= a) & (u + dx <= b) & (2.0 * jnp.abs(dx) <= jnp.abs(last))
        dx = jnp.where(ok, dx, 0.5 * (a + b) - u)
        return u + dx, a, b, dx

    u, _, _, _ = jax.lax.fori_loop(0, _STEPS, step, (0.5 * (lo + up), lo, up, up - lo))
    th = jnp.where(g(lo) <= 0, _TH_LO, jnp.exp(u))
    return jnp.where(g(up) >= 0, hi, th)


@_root.defjvp
def _root_jvp(fn, primals, tangents):
    y, lam, hi = primals
    ty, tlam, thi = tangents
    th = _root(fn, y, lam, hi)
    f_th = _d_theta(fn, th, lam)
    f_lam = jax.jvp(lambda lm: fn(th, lm), (lam,), (tlam,))[1]
    interior = (fn(hi, lam) < y) & (fn(jnp.full_like(y, _TH_LO), lam) > y)
    dth = (ty - f_lam) / jnp.minimum(f_th, -_SLOPE_FLOOR)
    clamped_hi = fn(hi, lam) >= y
    return th, jnp.where(interior, dth, jnp.where(clamped_hi, thi, 0.0))


def end_angle(lam: ArrayLike) -> jnp.ndarray:
    """theta_e(lam): end of the displacement-controlled branch, where dDelta/dA = 0
    (pi/2 - 1e-6, i.e. a -> 0, for lam < 0.938)."""
    return _solve(_delta_per_area, 0.0, lam, _TH_TOP)


def pull_off_angle(lam: ArrayLike) -> jnp.ndarray:
    """theta_c(lam): minimum of Pbar over A, the load-controlled pull-off."""
    return _solve(_load_per_area, 0.0, lam, _TH_TOP)


def angle_from_contact_radius(a_red: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """theta = arcsec m solving Maugis' m-equation at reduced radius A > 0 (A below
    A(pi/2 - 1e-6) ~ 1e-6 cbar is clamped there)."""
    return _solve(_radius, a_red, lam, _TH_TOP)


def angle_from_overlap(delta_red: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """theta(Delta) on the displacement-stable branch; theta_e below its end."""
    return _solve(_delta, delta_red, lam, end_angle(lam))


def angle_from_load(pbar: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """theta(Pbar) on the load-controlled branch; theta_c for Pbar below the pull-off."""
    return _solve(_load, pbar, lam, pull_off_angle(lam))


def reduced_pull_off(lam: ArrayLike) -> jnp.ndarray:
    """Pbar_c(lam) = min Pbar [-]: -2 (DMT, lam -> 0) to -3/2 (JKR, lam -> inf)."""
    return _load(pull_off_angle(lam), lam)


def reduced_end_overlap(lam: ArrayLike) -> jnp.ndarray:
    """Delta_e(lam) < 0 [-]: where the contact branch ends (JKR limit: -3 6^(-2/3))."""
    return _delta(end_angle(lam), lam)


def reduced_force(delta_red: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """Pbar(Delta) [-] on the stable branch; 0 below Delta_e (separated)."""
    d = jnp.asarray(delta_red, dtype=float)
    th = angle_from_overlap(d, lam)
    return jnp.where(d >= _delta(end_angle(lam), lam), _load(th, lam), 0.0)


def reduced_stiffness(delta_red: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """dPbar/dDelta [-] on the stable branch; 0 below Delta_e."""
    d = jnp.asarray(delta_red, dtype=float)
    th = angle_from_overlap(d, lam)
    return jnp.where(d >= _delta(end_angle(lam), lam), reduced_slope(th, lam), 0.0)


# --- physical units ---------------------------------------------------------------------------

def pull_off_force(*, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike,
                   lam: ArrayLike) -> jnp.ndarray:
    """Fc = -Pbar_c(lam) pi w R > 0 [N] (load-controlled; 3 pi gamma R to 4 pi gamma R)."""
    return -reduced_pull_off(lam) * scales(e_star=e_star, radius=radius, gamma=gamma)[2]


def minimum_overlap(*, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike,
                    lam: ArrayLike) -> jnp.ndarray:
    """delta_e = Delta_e(lam) d_s < 0 [m]: end of the contact branch (jump-out)."""
    return reduced_end_overlap(lam) * scales(e_star=e_star, radius=radius, gamma=gamma)[1]


def contact_radius(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
                   gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """a [m] under load F [N] (> 0 compressive), load-controlled branch (a_c below -Fc)."""
    a_s, _, fs = scales(e_star=e_star, radius=radius, gamma=gamma)
    return a_s * _radius(angle_from_load(load / fs, lam), lam)


def contact_state(a: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike,
                  lam: ArrayLike) -> dict[str, jnp.ndarray]:
    """State at contact radius a [m] > 0, on either branch (one root solve for m).

    Returns m = c/a [-], cohesive radius c [m], overlap delta [m], force F [N] and the
    slope dF/d(delta) along the equilibrium curve [N/m]; a <= 0 gives m = inf, zeros.
    """
    a_s, d_s, fs = scales(e_star=e_star, radius=radius, gamma=gamma)
    a = jnp.asarray(a, dtype=float)
    pos = a > 0
    th = angle_from_contact_radius(jnp.where(pos, a / a_s, 1.0), lam)
    m = 1.0 / jnp.cos(th)
    return {"m": jnp.where(pos, m, jnp.inf), "c": jnp.where(pos, m * a, 0.0),
            "overlap": jnp.where(pos, d_s * _delta(th, lam), 0.0),
            "force": jnp.where(pos, fs * _load(th, lam), 0.0),
            "stiffness": jnp.where(pos, fs / d_s * reduced_slope(th, lam), 0.0)}


def contact_radius_from_overlap(delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
                                gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """a(delta) [m] on the stable branch; 0 below delta_e."""
    a_s, d_s, _ = scales(e_star=e_star, radius=radius, gamma=gamma)
    d = jnp.asarray(delta, dtype=float) / d_s
    th = angle_from_overlap(d, lam)
    return jnp.where(d >= _delta(end_angle(lam), lam), a_s * _radius(th, lam), 0.0)


def force(delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike,
          lam: ArrayLike) -> jnp.ndarray:
    """F(delta) [N] on the stable branch (module docstring); 0 below delta_e."""
    _, d_s, fs = scales(e_star=e_star, radius=radius, gamma=gamma)
    return fs * reduced_force(jnp.asarray(delta, dtype=float) / d_s, lam)


def stiffness(delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike,
              lam: ArrayLike) -> jnp.ndarray:
    """Tangent stiffness K(delta) = dF/d(delta) [N/m] on the stable branch; 0 below delta_e."""
    _, d_s, fs = scales(e_star=e_star, radius=radius, gamma=gamma)
    return fs / d_s * reduced_stiffness(jnp.asarray(delta, dtype=float) / d_s, lam)


def static_overlap(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
                   gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """delta0 [m] under load F0 [N] (load-controlled branch; one root solve)."""
    _, d_s, fs = scales(e_star=e_star, radius=radius, gamma=gamma)
    return d_s * _delta(angle_from_load(jnp.asarray(load, dtype=float) / fs, lam), lam)


def linear_stiffness(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
                     gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """K0 = dF/d(delta) at delta0 [N/m]; 0 at the pull-off load."""
    _, d_s, fs = scales(e_star=e_star, radius=radius, gamma=gamma)
    return fs / d_s * reduced_slope(angle_from_load(jnp.asarray(load, dtype=float) / fs, lam),
                                    lam)


def linear_frequency(load: ArrayLike, mass: ArrayLike, *, e_star: ArrayLike,
                     radius: ArrayLike, gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """f0 = (1/2 pi)(K0/m)^(1/2) [Hz], mass m [kg]."""
    k0 = linear_stiffness(load, e_star=e_star, radius=radius, gamma=gamma, lam=lam)
    return safe_sqrt(k0 / mass) / (2.0 * jnp.pi)


def shift_first_order(x: ArrayLike, *, load: ArrayLike, e_star: ArrayLike, radius: ArrayLike,
                      gamma: ArrayLike, lam: ArrayLike,
                      reference_overlap: ArrayLike | None = None) -> jnp.ndarray:
    """First-order Delta f/f0 = <K(delta0 + delta_a sin t)>/(2 K0) - 1/2 [-].

    x = delta_a/delta_ref, delta_ref the MD delta0 unless ``reference_overlap`` [m] is
    given; quadrature by models.ladder.first_order.first_order_from_stiffness (K = 0 where delta <=
    0).
    """
    kw = {"e_star": e_star, "radius": radius, "gamma": gamma, "lam": lam}
    d0 = static_overlap(load, **kw)
    x = jnp.asarray(x, dtype=float)
    x_own = x if reference_overlap is None else x * reference_overlap / d0
    return first_order_from_stiffness(lambda d: stiffness(d, **kw), d0, x_own,
                                      k0=linear_stiffness(load, **kw))


def modulus_from_frequency(f0: ArrayLike, load: ArrayLike, mass: ArrayLike, *,
                           radius: ArrayLike, gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """E* [Pa] that puts the linear resonance at f0 [Hz] under F0 [N], at fixed lam.

    Pbar0 = F0/(pi w R) does not involve E*, so theta0 and k0 = dPbar/dDelta follow from
    (Pbar0, lam) alone, and K0 = (pi w)^(1/3) R^(2/3) K^(2/3) k0 with K = 4 E*/3.
    """
    fs = jnp.pi * work_of_adhesion(gamma) * radius
    th = angle_from_load(jnp.asarray(load, dtype=float) / fs, lam)
    k0 = mass * jnp.square(2.0 * jnp.pi * f0)
    kk = (k0 / (reduced_slope(th, lam) * jnp.cbrt(fs * radius))) ** 1.5
    return 0.75 * kk


def overlap_from_frequency(f0: ArrayLike, load: ArrayLike, mass: ArrayLike, *,
                           radius: ArrayLike, gamma: ArrayLike, lam: ArrayLike,
                           e_star: ArrayLike | None = None) -> jnp.ndarray:
    """delta0 = F_s Delta0 k0 / (m (2 pi f0)^2) [m] at fixed lam: E* drops out (as in
    models.laws.jkr); ``e_star`` is accepted for signature compatibility and NOT used.

    With lam as the law parameter, the cohesive stress sigma0 ~ lam E*^(2/3) follows E*.
    """
    del e_star
    fs = jnp.pi * work_of_adhesion(gamma) * radius
    th = angle_from_load(jnp.asarray(load, dtype=float) / fs, lam)
    k0 = mass * jnp.square(2.0 * jnp.pi * f0)
    return fs * _delta(th, lam) * reduced_slope(th, lam) / k0
