"""The Maugis-Dugdale oscillator with its restoring force in parametric form.

Why. The Maugis-Dugdale force is implicit: F(delta) needs a root solve for Maugis' angle
theta = arcsec(c/a) at every delta (:mod:`models.laws.maugis_dugdale`). The generic exact
backbone (:mod:`models.ladder.generic`) averages the restoring force over thousands of intervals
per orbit, each by a 97-node quadrature of F, with a root solve at every node. Here the
mean restoring force over an interval is an integral along the branch in theta, where the
state is explicit:

    <Pbar>_[Delta_a, Delta_b] = Int Pbar(theta) Delta'(theta) dtheta / Int Delta'(theta) dtheta

over theta from theta(Delta_b) to theta(Delta_a) (Delta' = dDelta/dtheta),

16-point Gauss-Legendre in u = ln theta (the state's power laws in theta become
exponentials in u; 16 nodes agree with 48 to 3e-14 over q in [-1, 50]). The numerator and
the denominator carry the same interval length, so the ratio has no cancellation however
short the interval (the generic form's reason for integrating instead of differencing the
potential). Only the two ends need a root theta(Delta): linear interpolation on a grid of
512 angles (ln theta from ln 1e-7 to the branch end), then 4 Newton steps in u on
asinh Delta (quadratic convergence from the grid's ~1e-4 start), differentiated by the
implicit function theorem (custom_jvp, exact to every order: the Lindstedt coefficient
needs the third derivative).

In the relative coordinate q = delta/delta0 - 1 of :mod:`models.ladder.generic`, with reduced
units (Delta = delta/d_s, Pbar = F/F_s, :func:`models.laws.maugis_dugdale.scales`):

    P'(q) = [Pbar(Delta0 (1 + q)) - Pbar0] / (k0 Delta0),   k0 = dPbar/dDelta at Delta0,

and the flight acceleration Pbar0/(k0 Delta0) below the contact edge q = -1 (the surfaces
part at delta = 0, as for every law in the generic backbone). The law passes
:func:`restoring_force` to :class:`models.law.Physics` (``restoring_force``), so every
generic rung that uses the restoring force (backbone, contact-loss onset, Lindstedt series)
uses this form; tested against the generic quadrature of the force
(tests/test_maugis_dugdale_orbit.py).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.laws.maugis_dugdale import contact

__all__ = ["reduced_oscillator", "restoring_force", "angle_grid", "log_angle_from_overlap"]

_GRID = 512
_NEWTON = 4
# numpy (float64) here, made JAX arrays where used: a jnp array created on import would
# be float32 whenever float64 is switched on after the import (it is set at entry points)
_GL_T, _GL_W = np.polynomial.legendre.leggauss(16)


def _delta(th, lam):
    return contact.angle_state(th, lam)[2]


def _delta_per_log(u, lam):
    # dDelta/du at theta = e^u (negative on the stable branch)
    th = jnp.exp(u)
    return jax.jvp(lambda t: _delta(t, lam), (th,), (th,))[1]


def angle_grid(lam: ArrayLike) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(asinh Delta, ln theta) [-] on 512 angles of the displacement-stable branch, from
    theta = 1e-7 to its end theta_e(lam), ordered by increasing Delta (the root's start)."""
    gu = jnp.linspace(math.log(1e-7), jnp.log(contact.end_angle(lam)) - 1e-9, _GRID)
    gs = jnp.arcsinh(_delta(jnp.exp(gu), lam))
    return gs[::-1], gu[::-1]


@jax.custom_jvp
def _log_angle(d, lam, grid_s, grid_u):
    s = jnp.arcsinh(d)
    u = jnp.interp(s, grid_s, grid_u)
    g = lambda v: jnp.arcsinh(_delta(jnp.exp(v), lam))

    def newton(_, v):
        val, slope = jax.jvp(g, (v,), (jnp.ones_like(v),))
        return v - (val - s) / slope

    return jax.lax.fori_loop(0, _NEWTON, newton, u)


@_log_angle.defjvp
def _log_angle_jvp(primals, tangents):
    d, lam, gs, gu = primals
    td, tlam = tangents[:2]     # the grid only starts the iteration: no tangent
    u = _log_angle(d, lam, gs, gu)
    d_lam = jax.jvp(lambda lm: _delta(jnp.exp(u), lm), (lam,), (tlam,))[1]
    return u, (td - d_lam) / _delta_per_log(u, lam)


def log_angle_from_overlap(delta_red: ArrayLike, lam: ArrayLike,
                           grid: tuple[jnp.ndarray, jnp.ndarray] | None = None) -> jnp.ndarray:
    """ln theta(Delta) [-] on the displacement-stable branch, Delta between the branch end
    Delta_e and Delta(theta = 1e-7) ~ 1e28 (the root of
    :func:`models.laws.maugis_dugdale.angle_from_overlap`); ``grid`` from :func:`angle_grid`
    when many calls share one lam."""
    lam = jnp.asarray(lam, float)
    gs, gu = angle_grid(lam) if grid is None else grid
    d = jnp.asarray(delta_red, float)
    return _log_angle(d, jnp.broadcast_to(lam, d.shape), gs, gu)


def reduced_oscillator(delta0_red: ArrayLike, lam: ArrayLike):
    """(P', divided, flight acceleration) of the Maugis-Dugdale oscillator about the
    reduced overlap Delta0 > 0 (module doc): P'(q), the mean of P' over [a, b] without
    cancellation, and Pbar0/(k0 Delta0) [-]; the signature of
    :func:`models.ladder.generic.restoring_force`."""
    lam = jnp.asarray(lam, float)
    grid = angle_grid(lam)
    uof = lambda d: _log_angle(d, jnp.broadcast_to(lam, jnp.shape(d)), *grid)
    th0 = jnp.exp(uof(jnp.asarray(delta0_red, float)))
    _, p0, d0 = contact.angle_state(th0, lam)
    scale = contact.reduced_slope(th0, lam) * d0
    accel = p0 / scale

    def u_of_q(q):
        return uof(jnp.maximum(d0 * (1.0 + q), 0.0))

    def dp(q):
        q = jnp.asarray(q, float)
        touching = q > -1.0
        th = jnp.exp(u_of_q(jnp.where(touching, q, 0.0)))
        return jnp.where(touching, (contact.angle_state(th, lam)[1] - p0) / scale, -accel)

    def contact_mean(a, b):
        # a < b, both >= -1: Gauss-Legendre in ln theta between the ends' roots
        ua, ub = u_of_q(a), u_of_q(b)
        u = 0.5 * (ua + ub)[..., None] + 0.5 * (ub - ua)[..., None] * _GL_T
        w = _GL_W * _delta_per_log(u, lam)
        return (jnp.sum(w * contact.angle_state(jnp.exp(u), lam)[1], axis=-1)
                / jnp.sum(w, axis=-1) - p0) / scale

    def divided(a, b):
        a, b = jnp.broadcast_arrays(jnp.asarray(a, float), jnp.asarray(b, float))
        lo, hi = jnp.minimum(a, b), jnp.maximum(a, b)
        ca, cb = jnp.maximum(lo, -1.0), jnp.maximum(hi, -1.0)
        wide = cb > ca
        mean = jnp.where(wide, contact_mean(ca, jnp.where(wide, cb, ca + 1e-3)), dp(ca))
        # the part of [lo, hi] below the contact edge flies: constant P' = -accel
        span = hi - lo
        flying = jnp.where(span > 0, jnp.clip(-1.0 - lo, 0.0, None)
                           / jnp.where(span > 0, span, 1.0), (hi <= -1.0).astype(float))
        return flying * (-accel) + (1.0 - flying) * mean

    return dp, divided, accel


def restoring_force(*, delta0: ArrayLike, e_star: ArrayLike, radius: ArrayLike,
                    gamma: ArrayLike, lam: ArrayLike, **_):
    """:func:`reduced_oscillator` at the physical overlap delta0 [m] (Delta0 = delta0/d_s):
    the law's ``restoring_force`` (:class:`models.law.Physics`)."""
    _, d_s, _ = contact.scales(e_star=e_star, radius=radius, gamma=gamma)
    return reduced_oscillator(jnp.asarray(delta0, float) / d_s, lam)
