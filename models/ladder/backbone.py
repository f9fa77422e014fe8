"""Exact free-vibration backbone of the conservative contact oscillator (ladder rung 3).

Conservative oscillator in the relative coordinate q = delta/delta0 - 1 (see
models/ladder/oscillator.py): q'' + P'(q) = 0 with potential P(0) = 0 at the static
equilibrium. For a power law F ~ delta^n (slope s = n, y = 1 + q):

    P(q) = [ y^(n+1)/(n+1) - y + n/(n+1) ] / n      (y > 0),
    P(q) = 1/(n+1) - (q + 1)/n                      (y <= 0: free flight, q'' = 1/n).

An orbit of energy P(qmax) between turning points qmin < 0 < qmax has half period
T/2 = int dq / sqrt(2 (P(qmax) - P(q))). The endpoint square-root singularities are
removed by q = c + h cos(theta) (theta in [0, pi]), which makes dtau/dtheta smooth,
so Gauss-Legendre in theta converges spectrally; tau(theta) is the cumulative
integral (nested Gauss-Legendre). If the orbit leaves contact (P(qmax) > P(-1)) the
contact arc q in [-1, qmax] uses q = -1 + (qmax + 1) cos^2(phi) and the flight arc
is a parabola, integrated in closed form for the period and by Gauss-Legendre for
the Fourier integral. Just past contact-loss onset the speed at q = -1 is small and the
contact arc's integrand has complex singularities close to phi = pi/2: that arc uses a
composite rule graded towards pi/2, fixed whatever ``nodes``: about 1e-12 against an
mpmath energy integral (tests/test_backbone.py), where one 48-node rule would be off by
up to 1e-4 in the period and the amplitude root solve near x_c by 1e-5. ``nodes`` sets the
contact-only orbit's rule (48 are within ~1e-12 up to the onset) and the flight
parabola's. The energy gaps next to the turning points are formed without subtracting
nearly equal q (2h sin^2, 2h cos^2): subtracting, with 256 nodes the nested nodes would
round onto qmax and the gap to 0 (NaN).

Amplitude (the project convention, what a vibrometer reads): x = first-harmonic amplitude of q,
a1 = (4/T) int_0^(T/2) q(tau) cos(omega tau) dtau (the orbit is even about qmax), so
x is not (qmax - qmin)/2. Frequency ratio omega/omega0 = 2 pi/T; the backbone is
Delta f/f0 = 2 pi/T - 1 at first-harmonic amplitude x, found by a root solve in qmax.

The Lindstedt-Poincare series (rung 1) for q'' + q + a2 q^2 + a3 q^3 = 0 is
omega = 1 + (3 a3/8 - 5 a2^2/12) a^2 + O(a^4) (Nayfeh & Mook, *Nonlinear
Oscillations*, 1979, Sec. 4.1.1), a the first-harmonic amplitude (to this order any
amplitude definition that agrees at O(a) gives the same coefficient). Expanding
(1 + q)^n / n: a2 = (n - 1)/2, a3 = (n - 1)(n - 2)/6.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.ladder.quadrature import bisect as _bisect
from beadrod.models.ladder.quadrature import gauss_legendre as _gl
from beadrod.models.ladder.quadrature import polish as _polish
from beadrod.models.safe_math import safe_pow, safe_sqrt

__all__ = [
    "powerlaw_potential",
    "powerlaw_divided",
    "orbit",
    "powerlaw_orbit",
    "backbone_shift",
    "lindstedt_coefficient",
    "lindstedt_shift",
]

_N_NODES = 48
_N_PANELS = 24       # flight arc: graded panels reach (pi/4) 0.25^22 ~ 4e-14 of pi/2
_PANEL_RATIO = 0.25
_PANEL_NODES = 24    # Gauss nodes per panel: interpolant 3^-24 ~ 4e-12 (see _graded)


def powerlaw_potential(q: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """P(q) for F ~ delta^n, including the free-flight branch (y <= 0) [-]."""
    y = 1.0 + jnp.asarray(q)
    contact = (safe_pow(y, n + 1.0) / (n + 1.0) - y + n / (n + 1.0)) / n
    return jnp.where(y > 0, contact, 1.0 / (n + 1.0) - y / n)


def powerlaw_divided(a: ArrayLike, b: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """(P(b) - P(a))/(b - a), the mean restoring force on [a, b], without cancellation.

    With y_lo = 1 + min(a, b) > 0 and rho = |b - a|/y_lo:
    [y_lo^n expm1((n+1) log1p(rho)) / ((n+1) rho) - 1]/n. Falls back to the plain
    difference quotient where y_lo <= 1e-9 (contact edge, flight); a == b gives P'(a).
    """
    lo, d = jnp.minimum(a, b), jnp.abs(b - a)
    ylo = 1.0 + lo
    ok = ylo > 1e-9
    ys = jnp.where(ok, ylo, 1.0)
    rho = jnp.where(ok, d, 1.0) / ys
    # a == b (nodes that round onto a turning point): the limit P'(a), not 0/0
    pos = rho > 0
    rs = jnp.where(pos, rho, 1.0)
    ratio = jnp.where(pos, jnp.expm1((n + 1.0) * jnp.log1p(rs)) / ((n + 1.0) * rs), 1.0)
    fine = (jnp.power(ys, n) * ratio - 1.0) / n
    ds = jnp.where(ok, 1.0, d)
    coarse = (powerlaw_potential(jnp.where(ok, 0.0, b), n)
              - powerlaw_potential(jnp.where(ok, -1.0, a), n)) / jnp.where(ds > 0, ds, 1.0)
    return jnp.where(ok, fine, jnp.sign(b - a) * coarse)


def _contact_arc(divided, qmax, qmin, nodes):
    """tau(theta), q(theta), f = dtau/dtheta on GL nodes of theta in (0, pi).

    The energy gap P(qmax) - P(q) is written (qmax - q) <r>_[q, qmax] on the upper half
    and (q - qmin) <-r>_[qmin, q] on the lower half, so it keeps full relative precision
    at both turning points (no difference of nearly equal potentials); qmax - q =
    2h sin^2(theta/2) and q - qmin = 2h cos^2(theta/2) are formed without subtraction, which
    would round to 0 at the nested nodes next to the turning points of a fine rule.
    """
    th, w = _gl(nodes, 0.0, np.pi)
    c, h = 0.5 * (qmax + qmin), 0.5 * (qmax - qmin)

    def f(theta):
        q = c + h * jnp.cos(theta)
        upper = 2.0 * h * jnp.sin(0.5 * theta) ** 2 * divided(q, qmax)
        lower = -2.0 * h * jnp.cos(0.5 * theta) ** 2 * divided(qmin, q)
        gap = jnp.where(theta < np.pi / 2, upper, lower)
        return h * jnp.sin(theta) / safe_sqrt(2.0 * gap)

    fv = f(th)
    t, wt = _gl(nodes, 0.0, 1.0)
    tau = jnp.sum(wt * f(th[:, None] * t[None, :]), axis=1) * th
    return c + h * jnp.cos(th), fv, w, tau, jnp.sum(w * fv)


def _graded(a: float, b: float):
    """Composite Gauss-Legendre on [a, b], _N_PANELS panels shrinking geometrically (ratio
    _PANEL_RATIO) towards b, _PANEL_NODES nodes each: (nodes (P, m), weights (P, m), panel
    widths (P,)). A singularity at distance d from b (off the interval) is seen by each
    panel wider than d at a relative distance >= 2 ratio/(1 - ratio) = 2/3 of its
    half-width, where m-point Gauss converges as 3^(-2m) and the m-point interpolant (the
    partial integrals of :func:`_partial_integrals`) as 3^(-m); panels narrower than d see
    it farther. The last panel has width (b - a)/2 ratio^(P - 2); below that scale the
    integrand's feature is narrower than the panel and contributes O(d)."""
    ends = b - 0.5 * (b - a) * _PANEL_RATIO ** np.arange(_N_PANELS - 1)
    edges = np.concatenate([[a], ends, [b]])
    t, w = np.polynomial.legendre.leggauss(_PANEL_NODES)
    width = np.diff(edges)
    x = edges[:-1, None] + width[:, None] * (t + 1) / 2
    return jnp.asarray(x), jnp.asarray(width[:, None] * w / 2), jnp.asarray(width)


def _partial_matrix(m: int) -> np.ndarray:
    """S with (S f)_i = int_-1^t_i p(t) dt, p the interpolant of f on the m Gauss nodes t_i
    (spectral integration: Legendre coefficients, then their antiderivatives)."""
    t, _ = np.polynomial.legendre.leggauss(m)
    vander = np.polynomial.legendre.legvander(t, m - 1)
    anti = np.stack([np.polynomial.legendre.legval(t, np.polynomial.legendre.legint(
        np.eye(m)[j], lbnd=-1.0)) for j in range(m)], axis=1)
    return anti @ np.linalg.inv(vander)


def _flight_arc(divided, qmax, qc, accel, nodes):
    """Contact arc qmax -> qc (cos^2 map) then the flight parabola to qmin.

    Just past contact-loss onset the speed v at qc is small and dtau/dphi =
    2 span cos(phi) sin(phi)/sqrt(v^2 + (2 span/n) cos^2(phi) + ...) has complex
    singularities at a distance ~ v (n/(2 span))^(1/2) from phi = pi/2: the rule is graded
    towards pi/2 (:func:`_graded`; one Gauss rule on [0, pi/2] loses up to 1e-4 there), and
    tau at the nodes is the sum of the panels before plus the spectral partial integral in
    the node's own panel. ``nodes`` does not apply: the graded rule is fixed.
    """
    del nodes
    ph, w, width = _graded(0.0, np.pi / 2)
    span = qmax - qc

    def f(phi):
        q = qc + span * jnp.cos(phi) ** 2
        gap = span * jnp.sin(phi) ** 2 * divided(q, qmax)   # qmax - q without cancellation
        return 2.0 * span * jnp.cos(phi) * jnp.sin(phi) / safe_sqrt(2.0 * gap)

    fv = f(ph)
    per_panel = jnp.sum(w * fv, axis=1)
    before = jnp.cumsum(per_panel) - per_panel
    inner = 0.5 * width[:, None] * (fv @ jnp.asarray(_PARTIAL.T))
    tau = (before[:, None] + inner).ravel()
    speed = safe_sqrt(2.0 * span * divided(qc, qmax))
    t_f = speed / accel
    return (qc + span * jnp.cos(ph.ravel()) ** 2, fv.ravel(), w.ravel(), tau,
            jnp.sum(per_panel), speed, t_f)


_PARTIAL = _partial_matrix(_PANEL_NODES)


def orbit(qmax: ArrayLike, potential: Callable, divided: Callable, *, qmin_lo: ArrayLike,
          qc: ArrayLike | None = None, flight_accel: ArrayLike | None = None,
          nodes: int = _N_NODES) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """Exact periodic orbit of q'' + P'(q) = 0 through the turning point qmax > 0.

    ``potential`` P(q) must be increasing on [0, inf) and decreasing on [qmin_lo, 0];
    ``divided(a, b)`` = (P(b) - P(a))/(b - a) evaluated without cancellation. If ``qc``
    is given, below qc the motion is free flight with constant acceleration
    ``flight_accel`` > 0 (contact loss). Returns (omega, a1, qmin): frequency 2 pi/T [-],
    first-harmonic cosine amplitude of q [-], lower turning point [-].
    """
    qmax = jnp.asarray(qmax, dtype=float)
    lo = jnp.asarray(qmin_lo if qc is None else qc, dtype=float)
    if qc is None:
        flight = jnp.zeros_like(qmax, dtype=bool)
    else:
        flight = potential(qmax) > potential(qc)
    # contact-only orbit; qmax sanitised where the orbit flies (double-where)
    qm_c = jnp.where(flight, 0.5 * jnp.abs(lo), qmax)
    root_fn = lambda z: divided(z, qm_c)
    qmin_c = _polish(root_fn, _bisect(root_fn, lo * (1.0 - 1e-12), jnp.zeros_like(lo)))
    qs, fv, w, tau, half = _contact_arc(divided, qm_c, qmin_c, nodes)
    om_c = np.pi / half
    a1_c = 2.0 / half * jnp.sum(w * qs * jnp.cos(om_c * tau) * fv)
    if qc is None:
        return om_c, a1_c, qmin_c
    # orbit with a free-flight segment
    qm_f = jnp.where(flight, qmax, jnp.abs(qc) + 1.0)
    qs, fv, w, tau, tau_c, speed, t_f = _flight_arc(divided, qm_f, qc, flight_accel, nodes)
    half = tau_c + t_f
    om_f = np.pi / half
    s, ws = _gl(nodes, 0.0, 1.0)
    ts = s * t_f
    q_fl = qc - speed * ts + 0.5 * flight_accel * ts**2
    fl = t_f * jnp.sum(ws * q_fl * jnp.cos(om_f * (tau_c + ts)))
    a1_f = 2.0 / half * (jnp.sum(w * qs * jnp.cos(om_f * tau) * fv) + fl)
    qmin_f = qc - speed**2 / (2.0 * flight_accel)
    return (jnp.where(flight, om_f, om_c), jnp.where(flight, a1_f, a1_c),
            jnp.where(flight, qmin_f, qmin_c))


@partial(jax.jit, static_argnames="nodes")
def powerlaw_orbit(qmax: ArrayLike, n: ArrayLike = 1.5, nodes: int = _N_NODES):
    """:func:`orbit` for F ~ delta^n with contact loss at q = -1 (flight: q'' = 1/n)."""
    n = jnp.asarray(n, dtype=float)
    return orbit(qmax, lambda q: powerlaw_potential(q, n),
                 lambda a, b: powerlaw_divided(a, b, n), qmin_lo=-1.0, qc=-1.0,
                 flight_accel=1.0 / n, nodes=nodes)


def _qmax_of_x(x, n, nodes):
    """Turning point qmax whose orbit has first-harmonic amplitude x.

    a1(qmax) is smooth, monotone and close to the identity (a1 = qmax + O(qmax^2)),
    so plain Newton from qmax = x converges in a few steps for every x tested
    (0 < x <= 3); ``tests/test_backbone.py`` checks the amplitude it returns.
    """
    a1 = lambda qm: powerlaw_orbit(qm, n, nodes)[1] - x

    def newton(_, q):
        val, slope = jax.jvp(a1, (q,), (jnp.ones_like(q),))
        return jnp.maximum(q - val / slope, 0.5 * q)

    return jax.lax.fori_loop(0, 8, newton, x)


@partial(jax.custom_jvp, nondiff_argnums=(2,))
def _backbone_scalar(x, n, nodes):
    qmax = _qmax_of_x(x, n, nodes)
    return powerlaw_orbit(qmax, n, nodes)[0] - 1.0


@_backbone_scalar.defjvp
def _backbone_jvp(nodes, primals, tangents):
    # implicit function theorem: a1(qmax, n) = x fixes qmax(x, n)
    x, n = primals
    dx, dn = tangents
    qmax = _qmax_of_x(x, n, nodes)
    p = jnp.stack([qmax, n])
    om, jac = powerlaw_orbit(qmax, n, nodes)[0], jax.jacfwd(
        lambda v: jnp.stack(powerlaw_orbit(v[0], v[1], nodes)[:2]))(p)
    dq = (dx - jac[1, 1] * dn) / jac[1, 0]
    return om - 1.0, jac[0, 0] * dq + jac[0, 1] * dn


@partial(jax.jit, static_argnames="nodes")
def backbone_shift(x: ArrayLike, n: ArrayLike = 1.5, *, nodes: int = _N_NODES) -> jnp.ndarray:
    """Exact conservative backbone Delta f/f0 [-] at first-harmonic amplitude x = delta_a/delta0.

    F ~ delta^n (Hertz n = 3/2), weight preload, contact loss included (any x > 0; the
    orbit leaves contact for x above about 1). Differentiable in x and n (custom JVP:
    implicit function theorem through the amplitude root solve).
    """
    x, n = jnp.broadcast_arrays(jnp.asarray(x, dtype=float), jnp.asarray(n, dtype=float))
    safe_x = jnp.where(x > 1e-8, x, 1e-2)
    out = jax.vmap(lambda a, b: _backbone_scalar(a, b, nodes))(safe_x.ravel(), n.ravel())
    return jnp.where(x > 1e-8, out.reshape(x.shape), 0.0)


def lindstedt_coefficient(a2: ArrayLike, a3: ArrayLike) -> jnp.ndarray:
    """c in omega = 1 + c a^2 for q'' + q + a2 q^2 + a3 q^3 = 0: c = 3 a3/8 - 5 a2^2/12."""
    return 3.0 * a3 / 8.0 - 5.0 * a2**2 / 12.0


def lindstedt_shift(x: ArrayLike, n: ArrayLike = 1.5) -> jnp.ndarray:
    """Small-amplitude series Delta f/f0 = [3 a3/8 - 5 a2^2/12] x^2 for F ~ delta^n [-].

    a2 = (n-1)/2, a3 = (n-1)(n-2)/6: coefficient (n-1)(n-2)/16 - 5(n-1)^2/48
    (Hertz: -1/24, against the first-order average's (n-1)(n-2)/8 = -1/32).
    """
    n = jnp.asarray(n, dtype=float)
    c = lindstedt_coefficient((n - 1.0) / 2.0, (n - 1.0) * (n - 2.0) / 6.0)
    return c * jnp.square(jnp.asarray(x, dtype=float))
