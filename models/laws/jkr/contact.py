"""JKR adhesive contact of a sphere on a plane (paper Sec. 4.3, Eqs. 16-19): the mechanics.

The closed forms, the root solve and the first-order quadrature, with no contact-law
object: :mod:`models.laws.jkr.table` tabulates :func:`shift_first_order` from here, and
:mod:`models.laws.jkr` (the law, which uses that table) builds the law object from it, so
both depend on this module and not on each other.

With surface energy gamma [J/m^2] of each (identical) surface, the work of adhesion is
w = 2 gamma, and in terms of the contact radius a [m]::

    delta(a) = a^2/R - (2 pi w a / E*)^(1/2) = a^2/R - (4 pi gamma a / E*)^(1/2)     (Eq. 17)
    F(a)     = 4 E* a^3/(3R) - (8 pi w E* a^3)^(1/2)                              (Eq. 17)
    a^3(F)   = (3R/4E*) [F + 2 Fc + (4 F Fc + 4 Fc^2)^(1/2)],  Fc = (3/2) pi w R = 3 pi gamma R
    K = dF/d(delta) = 2 E* a [3 - 3 (ac/a)^(3/2)] / [3 - (ac/a)^(3/2)],  ac^3 = 3 Fc R/(4 E*)
                                                                                   (Eq. 19)
(the paper's Eq. 16 is garbled by extraction; the above is Johnson, Kendall & Roberts,
Proc. R. Soc. A 324, 301 (1971); K. L. Johnson, *Contact Mechanics*, Sec. 5.5). Eq. 19 is
exactly (dF/da)/(d delta/da): the tests check it against autodiff of the parametric pair.

Branches. ac is the contact radius at the load-controlled pull-off F = -Fc, where K = 0.
delta(a) has its minimum at a_min = ac / 9^(1/3) (displacement-controlled pull-off,
delta_min < 0, F = -(5/9) Fc, K -> -inf). The inverse delta -> a is taken on the branch
a >= a_min, on which delta(a) is increasing: this is the unloading (retraction) branch,
valid for delta >= delta_min; below delta_min the surfaces have separated and force and
stiffness are 0. (On approach the contact only forms at delta = 0, so for
delta_min < delta < 0 the state is history-dependent; for the small-amplitude shift
about delta0 > 0 with x <= 1 both branches coincide.)

Scaling used by the root solve: L = (pi gamma R^2/E*)^(1/3), a = L s^2 and
delta = (L^2/R) (s^4 - 2 s): a quartic in s, solved by Newton from above (convex,
increasing for s >= s_min = 2^(-1/3)) with the derivative supplied by the implicit
function theorem (custom_jvp), never by differentiating through the iterations.
"""

from __future__ import annotations

import sys

import jax
import jax.numpy as jnp
from jax.typing import ArrayLike

from beadrod.models.ladder.first_order import first_order_adhesive
from beadrod.models.safe_math import safe_pow, safe_sqrt

__all__ = [
    "pull_off_force",
    "critical_radius",
    "minimum_overlap",
    "contact_radius",
    "overlap_from_contact_radius",
    "force_from_contact_radius",
    "stiffness_from_contact_radius",
    "contact_radius_from_overlap",
    "static_overlap",
    "linear_stiffness",
    "linear_frequency",
    "stiffness",
    "force",
    "shift_first_order",
    "modulus_from_frequency",
    "overlap_from_frequency",
]

_S_MIN = 2.0 ** (-1.0 / 3.0)
_DBAR_MIN = -3.0 * 2.0 ** (-4.0 / 3.0)  # s_min^4 - 2 s_min
_NEWTON_STEPS = 80  # linear (factor 1/2) convergence at the double root: 2^-80 is plenty


def pull_off_force(*, gamma: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """Fc = 3 pi gamma R = (3/2) pi w R [N] (load-controlled pull-off)."""
    return 3.0 * jnp.pi * gamma * radius


def critical_radius(*, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike) -> jnp.ndarray:
    """ac = (3 Fc R/(4 E*))^(1/3) [m]: contact radius at F = -Fc, where K = 0 (Eq. 19)."""
    fc = pull_off_force(gamma=gamma, radius=radius)
    return jnp.cbrt(0.75 * fc * radius / e_star)


def _scales(e_star, radius, gamma):
    length = jnp.cbrt(jnp.pi * gamma * radius**2 / e_star)
    return length, length**2 / radius  # radius scale L, overlap scale L^2/R


def minimum_overlap(*, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike) -> jnp.ndarray:
    """delta_min = -3 2^(-4/3) L^2/R < 0 [m]: the displacement-controlled pull-off."""
    return _DBAR_MIN * _scales(e_star, radius, gamma)[1]


def contact_radius(
    load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """a [m] under load F [N] (> 0 compressive), stable (load-controlled) branch, closed form.

    Defined for F >= -Fc; below -Fc there is no equilibrium and the pull-off radius ac is
    returned. da/dF diverges like (F + Fc)^(-1/2) at F -> -Fc (true); at exactly -Fc the
    gradient reported is finite (safe_sqrt), not the infinite one.
    """
    fc = pull_off_force(gamma=gamma, radius=radius)
    bracket = load + 2.0 * fc + 2.0 * safe_sqrt(fc * (load + fc))
    return jnp.cbrt(0.75 * radius / e_star * jnp.maximum(bracket, fc))


def overlap_from_contact_radius(
    a: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """delta = a^2/R - (4 pi gamma a / E*)^(1/2) [m] (Eqs. 17-18)."""
    return jnp.square(a) / radius - safe_sqrt(4.0 * jnp.pi * gamma * a / e_star)


def force_from_contact_radius(
    a: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """F = 4 E* a^3/(3R) - (16 pi gamma E* a^3)^(1/2) [N] (Eqs. 17-18)."""
    a3 = safe_pow(a, 3.0)
    return 4.0 * e_star * a3 / (3.0 * radius) - safe_sqrt(16.0 * jnp.pi * gamma * e_star * a3)


def stiffness_from_contact_radius(
    a: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """K = 2 E* a [3 - 3 u]/[3 - u], u = (ac/a)^(3/2) [N/m] (Eq. 19); 0 for a <= 0.

    K > 0 for a > ac, K < 0 for a_min < a < ac, K -> -inf at a_min = ac/9^(1/3) (there a
    large negative finite number is returned instead of -inf).
    """
    pos = a > 0
    a_safe = jnp.where(pos, a, 1.0)
    u = safe_pow(critical_radius(e_star=e_star, radius=radius, gamma=gamma) / a_safe, 1.5)
    den = 3.0 - u
    den = jnp.where(jnp.abs(den) > 1e-300, den, 1e-300)
    return jnp.where(pos, 2.0 * e_star * a_safe * (3.0 - 3.0 * u) / den, 0.0)


@jax.custom_jvp
def _scaled_root(dbar: jnp.ndarray) -> jnp.ndarray:
    """s >= s_min with s^4 - 2 s = dbar (dbar clamped to >= dbar_min)."""
    return _newton(jnp.asarray(dbar))


@jax.jit  # cached per shape: keeps eager (un-jitted) callers from re-tracing the loop
def _newton(dbar: jnp.ndarray) -> jnp.ndarray:
    d = jnp.maximum(dbar, _DBAR_MIN)
    # f(s0) >= 0 for this start (checked for dbar <= 0, small and large dbar), so Newton
    # on the convex increasing f decreases monotonically onto the root.
    s0 = jnp.maximum(_S_MIN, safe_pow(d, 0.25)) + 1.3

    def step(_, s):
        fp = 4.0 * s**3 - 2.0
        fp = jnp.where(fp > 0, fp, 1.0)
        return jnp.maximum(s - (s**4 - 2.0 * s - d) / fp, _S_MIN)

    return jax.lax.fori_loop(0, _NEWTON_STEPS, step, s0)


@_scaled_root.defjvp
def _scaled_root_jvp(primals, tangents):
    (dbar,), (t,) = primals, tangents
    s = _scaled_root(dbar)
    # implicit function theorem: ds/d(dbar) = 1/f'(s); zero where clamped (separated);
    # the true derivative is infinite at dbar_min itself, kept finite by the floor.
    fp = jnp.maximum(4.0 * s**3 - 2.0, 1e-12)
    return s, jnp.where(dbar > _DBAR_MIN, t / fp, 0.0)


def contact_radius_from_overlap(
    delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """a(delta) [m] on the branch a >= a_min (see module docstring); 0 for delta < delta_min.

    Root solve with implicit-function gradients (w.r.t. delta, E*, R, gamma).
    """
    length, dscale = _scales(e_star, radius, gamma)
    dbar = jnp.asarray(delta) / dscale
    s = _scaled_root(dbar)
    return jnp.where(dbar >= _DBAR_MIN, length * s**2, 0.0)


def static_overlap(
    load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """delta0 [m] under load F0 [N]: delta(a(F0)), closed form (the cubic for a is explicit,
    so no root solve is needed here)."""
    a = contact_radius(load, e_star=e_star, radius=radius, gamma=gamma)
    return overlap_from_contact_radius(a, e_star=e_star, radius=radius, gamma=gamma)


def linear_stiffness(
    load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """K0 [N/m]: Eq. 19 at a(F0)."""
    a = contact_radius(load, e_star=e_star, radius=radius, gamma=gamma)
    return stiffness_from_contact_radius(a, e_star=e_star, radius=radius, gamma=gamma)


def linear_frequency(
    load: ArrayLike, mass: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """f0 = (1/2 pi) (K0/m)^(1/2) [Hz]; 0 at the pull-off load (K0 = 0)."""
    k0 = linear_stiffness(load, e_star=e_star, radius=radius, gamma=gamma)
    return safe_sqrt(k0 / mass) / (2.0 * jnp.pi)


def stiffness(
    delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """Tangent stiffness K(delta) [N/m] on the unloading branch; 0 for delta < delta_min."""
    a = contact_radius_from_overlap(delta, e_star=e_star, radius=radius, gamma=gamma)
    return stiffness_from_contact_radius(a, e_star=e_star, radius=radius, gamma=gamma)


def force(
    delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """F(delta) [N] on the unloading branch; 0 for delta < delta_min (separated)."""
    a = contact_radius_from_overlap(delta, e_star=e_star, radius=radius, gamma=gamma)
    return force_from_contact_radius(a, e_star=e_star, radius=radius, gamma=gamma)


def shift_first_order(
    x: ArrayLike,
    *,
    load: ArrayLike,
    e_star: ArrayLike,
    radius: ArrayLike,
    gamma: ArrayLike,
    reference_overlap: ArrayLike | None = None,
) -> jnp.ndarray:
    """First-order Delta f/f0 = <K(delta0 + delta_a sin t)>/(2 K0) - 1/2 [-].

    delta0 is the JKR static overlap. x = delta_a / delta_ref where delta_ref defaults to
    that delta0; pass ``reference_overlap`` (e.g. the Hertz delta0, as the paper's Fig. 4
    does) to use another normalisation. Quadrature by models.ladder.first_order.first_order_adhesive
    (which clips K to 0 where delta <= 0, i.e. for x_jkr > 1 only).
    """
    return first_order_adhesive(sys.modules[__name__], x, load=load, e_star=e_star,
                                radius=radius, gamma=gamma, reference_overlap=reference_overlap)


def modulus_from_frequency(
    f0: ArrayLike, load: ArrayLike, mass: ArrayLike, *, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """E* [Pa] that puts the JKR linear resonance at f0 [Hz] under load F0 [N], closed form.

    (a/ac)^3 = (1 + (1 + F0/Fc)^(1/2))^2 does not depend on E*, and
    K0 = 2 E*^(2/3) (3 Fc R/4)^(1/3) (a/ac) g(u), g = (3 - 3u)/(3 - u), u = (ac/a)^(3/2).
    """
    fc = pull_off_force(gamma=gamma, radius=radius)
    root = 1.0 + safe_sqrt(1.0 + load / fc)
    rho = jnp.cbrt(jnp.square(root))
    u = 1.0 / root
    g = (3.0 - 3.0 * u) / (3.0 - u)
    k0 = mass * jnp.square(2.0 * jnp.pi * f0)
    return safe_pow(k0 / (2.0 * jnp.cbrt(0.75 * fc * radius) * rho * g), 1.5)


def overlap_from_frequency(
    f0: ArrayLike,
    load: ArrayLike,
    mass: ArrayLike,
    *,
    radius: ArrayLike,
    gamma: ArrayLike,
    e_star: ArrayLike | None = None,
) -> jnp.ndarray:
    """delta0 [m] implied by a measured linear resonance f0 [Hz] under load F0 [N], mass m.

    As for Hertz (whose inverse does not need E*), f0, F0, R and gamma fix the state: E* is
    implied (:func:`modulus_from_frequency`) and delta0 follows in closed form. ``e_star``
    is accepted for signature compatibility with the other laws and is NOT used: a given
    E* together with f0 and F0 would over-determine the contact.
    """
    del e_star
    es = modulus_from_frequency(f0, load, mass, radius=radius, gamma=gamma)
    a = contact_radius(load, e_star=es, radius=radius, gamma=gamma)
    return overlap_from_contact_radius(a, e_star=es, radius=radius, gamma=gamma)
