"""Generic numerics for any contact law, from its force alone.

Given a :class:`models.law.ContactLaw` (force F(delta) [N], keyword parameters):

* :func:`static_overlap`: delta0 with F(delta0) = F0 (the ``load``), bisection in
  log delta then one Newton step for implicit-function gradients;
* :func:`overlap_from_frequency`: delta0 with F(delta0)/F'(delta0) = F0/(m omega0^2),
  the overlap a measured resonance implies when the protocols scatter by a stiffness
  scale s_p (F_p = s_p F, see :mod:`models.law`);
* :func:`first_order_shift`: the paper's first-order average
  Delta f/f0 = <K(delta0 (1 + x sin t))>/(2 K0) - 1/2, K = F' by autodiff, by tanh-sinh
  quadrature over the contact arc (split at the contact-loss angle when x > 1;
  :func:`models.ladder.first_order.first_order_from_stiffness`);
* :func:`backbone_shift`: the exact conservative backbone at first-harmonic amplitude x,
  by the energy-integral quadrature of :func:`models.ladder.backbone.orbit` through contact
  loss, with the law's restoring force in the relative coordinate q = delta/delta0 - 1:

      q'' + P'(q) = 0,   P'(q) = [F(delta0 (1 + q)) - F(delta0)] / (F'(delta0) delta0)

  (time in units of 1/omega0; the stiffness scale s_p cancels). Below the contact edge
  (q = -1: the surfaces part at delta = 0) the bead flies with q'' = F(delta0)/(K0 delta0).
  An adhesive law's force jumps there from F(0+) < 0 to 0: the conservative orbit
  then neglects the snap-in/snap-off hysteresis (its energy loss is damping, not a
  frequency change). The mean restoring force (P(b) - P(a))/(b - a) is the tanh-sinh
  integral of P' over [a, b]: no difference of nearly equal potentials.

These are exact references, too slow for a sampler: laws use closed forms and tables
as fast paths (:mod:`models.tables.surrogate`), and the tests compare both.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.models.ladder.backbone import orbit
from beadrod.models.ladder.quadrature import bisect, polish, tanh_sinh

__all__ = ["static_overlap", "overlap_from_frequency", "stiffness_scale_frequency",
           "frequency_of_force",
           "frequency_from_overlap", "stiffness", "first_order_shift",
           "restoring_force", "backbone_orbit", "backbone_shift", "lindstedt_coefficient",
           "contact_loss_turning_point", "contact_loss_onset"]

_LOG_LO, _LOG_HI = np.log(1e-14), np.log(1e-2)   # overlaps bracketed in [1e-14, 1e-2] m
# the divided differences of P: 49 nodes left up to 1e-6 in (P(b) - P(a))/(b - a) for the
# Greenwood-Williamson force (a C4 spline in D, ~100 knots in [-1, qc]; 2e-6 in its
# backbone, and contact-or-flight misjudged next to the onset); 97 nodes: 4e-9
_U, _W = tanh_sinh(97, h=5.6 / 96)
_FO_RULE = tanh_sinh(81, h=7.6 / 80)   # tails to 1e-16 of the ends: t^(n-1) at x = 1


def _force(law, kw):
    kw = {k: v for k, v in kw.items() if k not in ("delta0", "omega0")}
    return lambda d: law.physics.force(d, **kw)


def stiffness(law: Any, delta: Any, **kw: Any) -> jnp.ndarray:
    """Tangent stiffness K = dF/d delta [N/m] by forward-mode autodiff, elementwise."""
    f = _force(law, kw)
    d = jnp.asarray(delta, float)
    return jax.jvp(f, (d,), (jnp.ones_like(d),))[1]


def static_overlap(law: Any, **kw: Any) -> jnp.ndarray:
    """delta0 [m] with F(delta0) = load [N], F increasing (bisection in log delta)."""
    f = _force(law, kw)
    load = jnp.asarray(kw["load"], float)
    g = lambda u: f(jnp.exp(u)) - load
    lo = jnp.full(load.shape, _LOG_LO)
    u = polish(g, bisect(g, lo, jnp.full(load.shape, _LOG_HI), iters=80))
    return jnp.exp(u)


def overlap_from_frequency(law: Any, f0: Any, **kw: Any) -> jnp.ndarray:
    """delta0 [m] with F/F' = load/(m omega0^2) at omega0 = 2 pi f0 [Hz] (stiffness-scale
    scatter: F_p = s_p F, so F_p(delta0) = load and F_p'(delta0) = m omega0^2)."""
    f = _force(law, kw)
    target = kw["load"] / (kw["mass"] * jnp.square(2.0 * jnp.pi * jnp.asarray(f0, float)))

    def g(u):
        d = jnp.exp(u)
        val, k = jax.jvp(f, (d,), (jnp.ones_like(d),))
        return jnp.log(val / k) - jnp.log(target)

    lo = jnp.full(jnp.shape(target), _LOG_LO)
    u = polish(g, bisect(g, lo, jnp.full(jnp.shape(target), _LOG_HI), iters=80))
    return jnp.exp(u)


def frequency_of_force(force: Any, delta0: Any, *, load: Any, mass: Any) -> jnp.ndarray:
    """f0 = (load F'(delta0) / (m F(delta0)))^(1/2) / (2 pi) [Hz] for a force F(delta) [N]
    (one-argument callable), delta0 [m]: the stiffness-scale inverse of
    :func:`overlap_from_frequency` in closed form."""
    d = jnp.asarray(delta0, float)
    val, k = jax.jvp(force, (d,), (jnp.ones_like(d),))
    return jnp.sqrt(load * k / (mass * val)) / (2.0 * jnp.pi)


def stiffness_scale_frequency(law: Any, delta0: Any, **kw: Any) -> jnp.ndarray:
    """:func:`frequency_of_force` with the law's force and resolved keywords ``kw``."""
    return frequency_of_force(_force(law, kw), delta0, load=kw["load"], mass=kw["mass"])


def frequency_from_overlap(law: Any, delta0: Any, *, steps: int = 6,
                           guess: float = 2700.0, **kw: Any) -> jnp.ndarray:
    """f0 [Hz] with ``law.overlap_at(f0) = delta0`` [m], for a law whose own f0 -> delta0
    map has no closed-form inverse: Newton in log f0 on log delta0 from ``guess`` [Hz]
    (exact in one step where delta0 ~ f0^-2, which every smooth law nearly is; ``steps``
    guard the rest)."""
    target = jnp.log(jnp.asarray(delta0, float))
    u = jnp.full(target.shape, np.log(guess))

    def fn(uu):
        return jnp.log(law.overlap_at(jnp.exp(uu), **kw))

    for _ in range(steps):
        val, slope = jax.jvp(fn, (u,), (jnp.ones_like(u),))
        u = u - (val - target) / slope
    return jnp.exp(u)


def first_order_shift(law: Any, x: Any, *, delta0: Any, **kw: Any) -> jnp.ndarray:
    """First-order Delta f/f0 [-] at x = delta_a/delta0 from the autodiff stiffness.

    <K>/K0 = (1/pi) Int_0^phi0 K(delta0 (1 + x cos phi)) dphi / K0, phi0 = pi for x <= 1
    and arccos(-1/x) past contact loss (K = 0 where the surfaces part). Two tanh-sinh
    panels split at phi_s = phi0 - 2 (2 |1 - x|)^(1/2) (no earlier than phi0/2): just below
    x = 1 the integrand is nearly singular at phi0, at a distance ~ (2 (1 - x))^(1/2), and
    one panel loses 1e-10 there; the split keeps 1e-12 against the closed forms.
    NaN where the force is not finite somewhere on the contact arc (as the backbone,
    which integrates the force itself).
    """
    x = jnp.abs(jnp.asarray(x, float))
    d0 = jnp.broadcast_to(jnp.asarray(delta0, float), x.shape)
    k0 = stiffness(law, d0, **kw)
    xs = jnp.where(x > 1.0, x, 2.0)
    phi0 = jnp.where(x > 1.0, jnp.arccos(-1.0 / xs), jnp.pi)
    split = jnp.clip(phi0 - jnp.maximum(2.0 * jnp.sqrt(2.0 * jnp.abs(1.0 - x)), 0.5),
                     0.5 * phi0, phi0)
    u, w = (jnp.asarray(v) for v in _FO_RULE)

    def panel(a, b, ratio):
        # ratio(t): delta/delta0 at the nodes t in (a, b)
        t = a[..., None] + (b - a)[..., None] * u
        d = d0[..., None] * ratio(t)
        touching = d > 0.0
        safe = jnp.where(touching, d, d0[..., None])
        f, k = jax.jvp(_force(law, kw), (safe,), (jnp.ones_like(safe),))
        # the stiffness alone can be finite where the force is not (jnp.where(..., nan, F)
        # has a zero tangent): a NaN force over the arc is NaN here, as in the backbone
        k = jnp.where(jnp.isfinite(f), k, jnp.nan)
        return (b - a) * jnp.sum(w * jnp.where(touching, k, 0.0), axis=-1)

    near = lambda psi: (1.0 - x[..., None]) + 2.0 * x[..., None] * jnp.sin(0.5 * psi) ** 2
    # second panel in psi = pi - phi: 1 + x cos(phi) = (1 - x) + 2 x sin^2(psi/2), which
    # keeps its relative precision next to phi = pi (1 + cos(phi) there cancels to 0)
    mean = (panel(jnp.zeros_like(x), split, lambda t: 1.0 + x[..., None] * jnp.cos(t))
            + panel(jnp.pi - phi0, jnp.pi - split, near)) / jnp.pi
    return mean / (2.0 * k0) - 0.5


def restoring_force(law: Any, *, delta0: Any, **kw: Any):
    """(P', divided, flight acceleration) of the dimensionless oscillator (module doc); the
    law's own exact form where it gives one (:class:`models.law.ContactLaw`)."""
    if law.physics.restoring_force is not None:
        return law.physics.restoring_force(delta0=delta0, **{k: v for k, v in kw.items()
                                                             if k != "omega0"})
    f = _force(law, kw)
    d0 = jnp.asarray(delta0, float)
    f0, k0 = jax.jvp(f, (d0,), (jnp.ones_like(d0),))
    scale = k0 * d0

    def dp(q):
        d = d0 * (1.0 + q)
        touching = d > 0.0
        inside = (f(jnp.where(touching, d, d0)) - f0) / scale
        return jnp.where(touching, inside, -f0 / scale)

    u, w = jnp.asarray(_U), jnp.asarray(_W)

    def divided(a, b):
        a, b = jnp.broadcast_arrays(jnp.asarray(a, float), jnp.asarray(b, float))
        pts = a[..., None] + (b - a)[..., None] * u
        return jnp.sum(w * dp(pts), axis=-1)

    return dp, divided, f0 / scale


def backbone_orbit(law: Any, qmax: Any, *, delta0: Any, nodes: int = 48, **kw: Any):
    """(omega/omega0, first-harmonic amplitude x, qmin) of the orbit through qmax."""
    _, divided, accel = restoring_force(law, delta0=delta0, **kw)
    potential = lambda q: q * divided(jnp.zeros_like(q), q)
    return orbit(qmax, potential, divided, qmin_lo=-1.0, qc=-1.0, flight_accel=accel,
                 nodes=nodes)


def contact_loss_turning_point(law: Any, *, delta0: Any, **kw: Any) -> jnp.ndarray:
    """qmax_c with P(qmax_c) = P(-1): the orbit through it just touches the contact edge."""
    _, divided, _ = restoring_force(law, delta0=delta0, **kw)
    p_edge = -divided(-1.0, 0.0)          # P(-1) = -(P(0) - P(-1))
    g = lambda q: q * divided(jnp.zeros_like(q), q) - p_edge
    return bisect(g, jnp.asarray(1e-9), jnp.asarray(50.0), iters=80)


_ONSET = 1e-9   # relative offset of the contact-only orbit that stands for the onset
_FLY = 1e-8     # relative offset of the first flying orbit the amplitude solve evaluates


def contact_loss_onset(law: Any, *, delta0: Any, **kw: Any) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(x_c, Delta f/f0 at x_c) [-]: the backbone where contact loss starts, the limit of
    the contact-only orbits, taken on the one through qmax_c (1 - 1e-9). Not at qmax_c
    itself: there the contact-or-flight test and the lower turning point's bracket compare
    energies equal to within the quadrature's rounding (~1e-12), and picked the wrong branch
    (x_c alternating between 0.92 and 0.84 from one Greenwood-Williamson table node to the
    next). Not on the flight side either: where the force jumps at the contact edge (an
    adhesive law: F(0+) < 0, 0 in flight) the flying orbits' x and Delta f/f0 move like the
    square root of qmax - qmax_c, so an orbit 1e-6 past the onset sits 3e-4 away in x and
    7e-4 in Delta f/f0 (JKR at F0/Fc = 0.6); the contact-only orbits move linearly."""
    qc = contact_loss_turning_point(law, delta0=delta0, **kw)
    om, a1, _ = backbone_orbit(law, qc * (1.0 - _ONSET), delta0=delta0, **kw)
    return a1, om - 1.0


def lindstedt_coefficient(law: Any, *, delta0: Any, **kw: Any) -> jnp.ndarray:
    """c in Delta f/f0 = c x^2 + O(x^4): 3 a3/8 - 5 a2^2/12 with P'(q) = q + a2 q^2 + a3 q^3
    (Nayfeh & Mook 1979, Sec. 4.1.1); a2, a3 by autodiff of P' at q = 0."""
    dp, _, _ = restoring_force(law, delta0=delta0, **kw)
    d2 = jax.grad(jax.grad(dp))
    a2 = d2(0.0) / 2.0
    a3 = jax.grad(d2)(0.0) / 6.0
    return 3.0 * a3 / 8.0 - 5.0 * a2**2 / 12.0


def backbone_shift(law: Any, x: Any, *, delta0: Any, nodes: int = 48,
                   **kw: Any) -> jnp.ndarray:
    """Exact backbone Delta f/f0 [-] at first-harmonic amplitude x (elementwise in x).

    The orbit's amplitude a1 grows with its upper turning point qmax, linearly below the
    onset of contact loss qmax_c and, past it, like (qmax - qmax_c)^(1/2) where the force
    jumps at the contact edge (adhesive laws; :func:`contact_loss_onset`). So the root of
    a1 = x is found by Newton in z with qmax = qmax_c + z below the onset (z < 0) and
    qmax_c + z^2 past it (z > 0), where a1 is smooth on each side with finite slopes
    (Newton in qmax from x failed there: values off by up to 0.05 within 0.02 of the onset
    for JKR at F0/Fc = 0.6). Then one Newton step in z from the stopped-gradient root, so
    gradients follow the implicit function theorem.
    """
    x = jnp.asarray(x, float)
    d0 = jnp.broadcast_to(jnp.asarray(delta0, float), x.shape)

    def one(xi, di):
        orbit_at = lambda qm: backbone_orbit(law, qm, delta0=di, nodes=nodes, **kw)[:2]
        qc = jax.lax.stop_gradient(contact_loss_turning_point(law, delta0=di, **kw))
        # within ~1e-10 of qmax_c the contact-or-flight test compares energies equal to
        # rounding (NaN at 1e-12): the orbits from qc (1 - 1e-9) to qc (1 + 1e-8) are
        # bridged linearly in z, where (a1, omega) are smooth to ~1e-8 on either side
        z_lo, z_hi = -_ONSET * qc, jnp.sqrt(_FLY * qc)
        ends = jax.lax.stop_gradient(jnp.stack([jnp.stack(orbit_at(qc + z_lo)),
                                                jnp.stack(orbit_at(qc + z_hi**2))]))
        qm_of = lambda z: qc + jnp.where(z > 0.0, z * z, z)

        def state(z):   # (omega, a1)
            bridge = (z > z_lo) & (z < z_hi)
            far = jnp.stack(orbit_at(qm_of(jnp.where(bridge, z_hi, z))))
            t = (z - z_lo) / (z_hi - z_lo)
            return jnp.where(bridge, ends[0] + t * (ends[1] - ends[0]), far)

        a1_z = lambda z: state(z)[1] - xi

        def newton(_, z):
            val, slope = jax.jvp(a1_z, (z,), (jnp.ones_like(z),))
            step = -val / jnp.where(slope > 0.0, slope, 1.0)
            # keep qmax > 0, and steps within twice the iterate's distance from the onset
            room = jnp.maximum(2.0 * jnp.abs(z), 0.05)
            return jnp.clip(z + jnp.clip(step, -room, room), -0.999 * qc, None)

        safe = jnp.where(xi > 1e-8, xi, 1e-2)
        xc = ends[0, 1]
        z0 = jnp.where(safe <= xc, (safe / xc - 1.0) * qc,
                       jnp.sqrt(jnp.maximum(safe - xc, 0.0)))
        z = polish(a1_z, jax.lax.fori_loop(0, 16, newton, z0))
        return jnp.where(xi > 1e-8, state(z)[0] - 1.0, 0.0)

    flat = jax.vmap(one)(x.ravel(), d0.ravel())
    return flat.reshape(x.shape)
