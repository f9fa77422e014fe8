"""Greenwood-Tripp rough sphere on a flat: the reference solver (NumPy/SciPy, offline).

The bulk sphere deforms elastically under the nominal pressure that a Greenwood-Williamson
(GW) layer of asperities carries (Greenwood & Tripp, J. Appl. Mech. 34, 153 (1967);
K. L. Johnson, *Contact Mechanics* (CUP 1985), Sec. 13.4). The combined roughness sits on
the flat; both bodies are elastic with the combined modulus E*.

Summits: density eta [1/m^2], radius beta [m], heights Gaussian with rms sigma [m] about
their mean plane, truncated at ``SUMMIT_CUTOFF`` s_c = 6 sigma (no summit higher; the mass
cut off is 1e-9, and it gives the contact a definite edge, see below). A mean-plane gap d
carries the GW nominal pressure (Greenwood & Williamson, Proc. R. Soc. A 295, 300 (1966))

    p(d) = (4/3) eta E* beta^(1/2) sigma^(3/2) F_{3/2}(d/sigma),
    F_n(h) = int_h^{s_c} (s - h)^n phi(s) ds,   phi the standard normal density.

Scales: lengths normal to the surface in sigma, radii in l = (R sigma)^(1/2), pressure in
p* = E* (sigma/R)^(1/2), force in F* = E* R^(1/2) sigma^(3/2). With the approach D =
delta/sigma of the sphere's far field (D = 0: the undeformed apex touches the summits'
mean plane) the dimensionless problem is

    h(rho) = -D + rho^2/2 + W(rho),                 gap [sigma]
    P(rho) = (mu / (2 sqrt 2)) F_{3/2}(h(rho)),      pressure [p*]
    W(rho) = (4/pi) int_0^inf P(t) t/(t + rho) K(k) dt,  k = 2 (rho t)^(1/2)/(rho + t)
    f(D)   = F/F* = 2 pi int_0^inf P rho d rho,

(Boussinesq, Johnson Eq. 3.96a) with one parameter, Johnson's mu = (8/3) eta sigma
(2 R beta)^(1/2). Johnson's roughness parameter at a load F is alpha = sigma R/a0^2 =
sigma/delta_H(F) = (3 f/4)^(-2/3) (a0, delta_H: Hertz contact radius and approach).
Truncation makes P = 0 where h >= s_c, so f(D) = 0 exactly for D <= -s_c and the pressure
vanishes beyond rho = (2 (D + s_c))^(1/2) (W >= 0).

Method. Piecewise-constant pressure on N rings, collocation at the ring midpoints; the
influence of a uniformly loaded disc is closed form (Johnson Eqs. 3.28-3.29: w(r) =
(4 p a/(pi E*)) E(r/a) inside, (4 p r/(pi E*)) [E(a/r) - (1 - a^2/r^2) K(a/r)] outside),
an annulus being the difference of two discs. Newton's method on the gap h, with the
exact Jacobian I + A diag((3/2) c F_{1/2}(h)) (solved by preconditioned GMRES) and a
backtracking line search. The error
is O(N^-2) and smooth, so Richardson extrapolation from N and 2N rings is used: measured
relative error of f <= 3e-8 for N = 200/400 (against 800/1600) at D in [-4, 1e4].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse.linalg import LinearOperator, gmres
from scipy.special import ellipe, ellipk, roots_legendre

__all__ = ["SUMMIT_CUTOFF", "MU_DEFAULT", "gw_integral", "disc_displacement",
           "influence_matrix", "ring_grid", "Solution", "solve", "load_approach",
           "rigid_limit", "hertz_ratios"]

SUMMIT_CUTOFF = 6.0
"""s_c: summit heights are truncated at s_c sigma above their mean plane [-]."""

MU_DEFAULT = 4.0
"""Johnson's mu = (8/3) eta sigma (2 R beta)^(1/2) used by the law (see greenwood_williamson)."""

_GL_U, _GL_W = roots_legendre(160)
_GL_U, _GL_W = 0.5 * (_GL_U + 1.0), 0.5 * _GL_W
_H_SERIES = -10.0          # below: the large-|h| expansion (its error ~ exp(-h^2/2))


def _phi(x):
    return np.exp(-0.5 * np.square(x)) / math.sqrt(2.0 * math.pi)


def _binom(n: float, k: int) -> float:
    out = 1.0
    for i in range(k):
        out *= (n - i) / (i + 1)
    return out


def _tail_moments(cutoff: float, kmax: int = 8) -> list[float]:
    """M_k = int_0^inf t^k phi(t + cutoff) dt (Gauss-Legendre on [0, 20])."""
    u, w = roots_legendre(200)
    t, w = 10.0 * (u + 1.0), 10.0 * w
    return [float(np.sum(w * t**k * _phi(t + cutoff))) for k in range(kmax)]


def gw_integral(n: float, h: np.ndarray, *, cutoff: float = SUMMIT_CUTOFF) -> np.ndarray:
    """F_n(h) = int_h^cutoff (s - h)^n phi(s) ds [-] (n > 0; cutoff = inf: the standard GW
    integral; Greenwood & Williamson 1966, Greenwood & Tripp 1970).

    h >= -10: s - h = L u^2 (L = cutoff - h), 160-point Gauss-Legendre in u (the integrand
    2 u^(2n+1) phi(h + L u^2) L^(n+1) is smooth). h < -10: E[(s - h)^n] = sum_k C(n, 2k)
    (2k-1)!! |h|^(n-2k) (asymptotic; 12 terms, error ~ phi(h)) minus the part above the
    cutoff, sum_k C(n, k) (cutoff - h)^(n-k) M_k. Relative error <= 1e-13 (tested).
    """
    h = np.asarray(h, float)
    out = np.zeros_like(h)
    finite = math.isfinite(cutoff)
    top = cutoff if finite else 40.0          # phi(40) underflows: the standard F_n
    mid = (h < top) & (h >= _H_SERIES)
    hm = h[mid][:, None]
    span = top - hm
    vals = 2.0 * _GL_U ** (2 * n + 1) * _phi(hm + span * _GL_U**2)
    out[mid] = span[:, 0] ** (n + 1) * (vals @ _GL_W)
    low = h < _H_SERIES
    x = -h[low]
    series, dfact = np.zeros_like(x), 1.0
    for k in range(12):
        dfact *= (2 * k - 1) if k else 1.0
        series += _binom(n, 2 * k) * dfact * x ** (n - 2 * k)
    if finite:
        span = cutoff - h[low]
        series -= sum(_binom(n, k) * span ** (n - k) * m
                      for k, m in enumerate(_tail_moments(cutoff)))
    out[low] = series
    return out


def disc_displacement(r: np.ndarray, a: np.ndarray) -> np.ndarray:
    """W(r; a) [sigma, for unit pressure p*]: normal displacement at radius r of a unit
    uniform pressure on a disc of radius a (Johnson Eqs. 3.28-3.29, combined modulus):
    (4/pi) a E(r/a) for r < a, (4/pi) r [E(a/r) - (1 - a^2/r^2) K(a/r)] for r >= a.
    Broadcasting r[:, None] against a[None, :]; scipy's E, K take m = k^2."""
    r, a = np.broadcast_arrays(np.asarray(r, float)[:, None], np.asarray(a, float)[None, :])
    inside = r < a
    m_in = np.where(inside, np.square(r / np.where(a > 0, a, 1.0)), 0.0)
    m_out = np.where(inside, 0.0, np.square(a / np.where(r > 0, r, 1.0)))
    w_in = a * ellipe(m_in)
    w_out = r * (ellipe(m_out) - (1.0 - m_out) * ellipk(m_out))
    return 4.0 / np.pi * np.where(inside, w_in, w_out)


def influence_matrix(edges: np.ndarray, points: np.ndarray) -> np.ndarray:
    """A[i, j]: W at points[i] of unit pressure on the ring edges[j] < r < edges[j+1]."""
    u = disc_displacement(points, edges)
    return u[:, 1:] - u[:, :-1]


def ring_grid(approach: float, n_rings: int) -> tuple[np.ndarray, np.ndarray]:
    """(edges, midpoints) on [0, (2 (D + s_c))^(1/2)], outside which P = 0 exactly.

    For D > 4 half the rings are clustered (Gaussian density of width 3.5 D^(-1/6),
    the distance over which the Hertz gap outside contact opens by ~4 sigma) about the
    Hertz edge rho = D^(1/2), where the pressure falls to 0.
    """
    rmax = math.sqrt(2.0 * (approach + SUMMIT_CUTOFF))
    s = np.linspace(0.0, 1.0, n_rings + 1)
    if approach <= 4.0:
        edges = rmax * s
    else:
        edge, width = math.sqrt(approach), 3.5 * approach ** (-1.0 / 6.0)
        x = np.linspace(0.0, rmax, 20001)
        dens = 1.0 / rmax + np.exp(-np.square((x - edge) / width)) / (math.sqrt(np.pi) * width)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(x))])
        edges = np.interp(s, cum / cum[-1], x)
    return edges, 0.5 * (edges[1:] + edges[:-1])


def _linear_solve(jac: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    # GMRES with a Jacobi preconditioner (12-60 iterations) instead of LAPACK: a dense
    # multithreaded factorisation is far slower on a loaded machine with few cores
    inv_diag = 1.0 / np.diag(jac)
    prec = LinearOperator(jac.shape, matvec=lambda x: inv_diag * x)
    x, info = gmres(jac, rhs, rtol=1e-13, atol=0.0, restart=min(200, rhs.size),
                    maxiter=20, M=prec)
    if info != 0:
        x = np.linalg.solve(jac, rhs)
    return x


@dataclass(frozen=True)
class Solution:
    """A converged Greenwood-Tripp state (dimensionless, see the module docstring)."""

    approach: float        # D [sigma]
    mu: float
    edges: np.ndarray      # ring edges [l]
    rho: np.ndarray        # ring midpoints [l]
    gap: np.ndarray        # h [sigma]
    pressure: np.ndarray   # P [p*]
    force: float           # f = F/F*
    iterations: int


def solve(approach: float, *, mu: float = MU_DEFAULT, n_rings: int = 200,
          initial: Solution | None = None, tol: float = 1e-13,
          max_iter: int = 100) -> Solution:
    """Solve the Greenwood-Tripp problem at approach D (> -s_c) on ``n_rings`` rings.

    ``initial``: a solution at a nearby approach; its displacement W (interpolated in rho)
    starts Newton (continuation). Otherwise W = 0 (rigid sphere). Raises if Newton fails.
    """
    if approach <= -SUMMIT_CUTOFF:
        raise ValueError(f"no contact at D = {approach} <= -{SUMMIT_CUTOFF}")
    c = mu / (2.0 * math.sqrt(2.0))
    edges, rho = ring_grid(approach, n_rings)
    amat = influence_matrix(edges, rho)
    g0 = -approach + 0.5 * rho**2
    h = g0.copy()
    if initial is not None:
        w0 = initial.gap + initial.approach - 0.5 * initial.rho**2
        h = g0 + np.interp(rho, initial.rho, w0)

    def residual(h):
        return h - g0 - amat @ (c * gw_integral(1.5, h))

    res = residual(h)
    norm = np.max(np.abs(res))
    it = 0
    while norm > tol * (1.0 + np.max(np.abs(h))):
        if it == max_iter:
            raise RuntimeError(f"Greenwood-Tripp Newton did not converge at D = {approach}")
        jac = np.eye(n_rings) + amat * (1.5 * c * gw_integral(0.5, h))[None, :]
        step = _linear_solve(jac, -res)
        t = 1.0
        while True:
            trial = h + t * step
            res_t = residual(trial)
            norm_t = np.max(np.abs(res_t))
            if norm_t < (1.0 - 1e-4 * t) * norm or t < 1e-8:
                break
            t *= 0.5
        h, res, norm = trial, res_t, norm_t
        it += 1
    p = c * gw_integral(1.5, h)
    force = float(np.pi * np.sum(p * np.diff(edges**2)))
    return Solution(float(approach), float(mu), edges, rho, h, p, force, it)


def load_approach(approaches: np.ndarray, *, mu: float = MU_DEFAULT, n_rings: int = 200,
                  richardson: bool = True) -> np.ndarray:
    """f(D) = F/F* at each approach (continuation in increasing D); with ``richardson``
    the extrapolation (4 f_2N - f_N)/3 from N and 2N rings (module docstring)."""
    d = np.asarray(approaches, float)
    order = np.argsort(d)
    out = np.empty_like(d)
    prev: dict[int, Solution | None] = {n_rings: None, 2 * n_rings: None}
    for i in order:
        sols = {}
        for n in prev if richardson else (n_rings,):
            sols[n] = solve(float(d[i]), mu=mu, n_rings=n, initial=prev[n])
            prev[n] = sols[n]
        f = sols[n_rings].force
        out[i] = (4.0 * sols[2 * n_rings].force - f) / 3.0 if richardson else f
    return out


def rigid_limit(approach: np.ndarray, *, mu: float = MU_DEFAULT) -> np.ndarray:
    """f of a rigid sphere on the GW layer (W = 0), exact as the load -> 0 (D -> -s_c):
    2 pi c int_{-D}^{s_c} F_{3/2}(u) du = (4 pi/5) c F_{5/2}(-D), c = mu/(2 sqrt 2)."""
    c = mu / (2.0 * math.sqrt(2.0))
    return 0.8 * np.pi * c * gw_integral(2.5, -np.asarray(approach, float))


def hertz_ratios(sol: Solution) -> dict[str, float]:
    """Johnson's alpha = (3 f/4)^(-2/3), the central pressure over the Hertz one at the
    same load, p(0)/p0 (p0 = (2/pi) (3 f/4)^(1/3) p*), and a*/a0 = (p0/p(0))^(1/2), the
    radius of the Hertz distribution with the same load and central pressure."""
    e = (0.75 * sol.force) ** (2.0 / 3.0)
    # P(rho) is even in rho: extrapolate the two innermost rings in rho^2 to rho = 0
    r1, r2 = sol.rho[0] ** 2, sol.rho[1] ** 2
    p_centre = (sol.pressure[0] * r2 - sol.pressure[1] * r1) / (r2 - r1)
    ratio = p_centre / (2.0 / np.pi * math.sqrt(e))
    return {"alpha": 1.0 / e, "central_pressure": float(ratio),
            "effective_radius": float(ratio ** -0.5)}
