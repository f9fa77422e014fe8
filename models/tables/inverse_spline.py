"""Inverses of increasing functions of one variable: a Newton solve (the reference) and a
tabulated spline of it (the fast path for samplers).

Why a table. A NumPyro likelihood that inverts a law's load-approach curve for every
protocol (the static overlap under the load, the overlap a measured f0 implies) pays for
a Newton loop on each gradient evaluation: on the CPU an XLA while loop costs about as much
as the rest of the likelihood. The inverse of a fixed curve is itself a fixed curve, so it
is tabulated once, when
the law's forward table is built, and read like any other spline: one cell lookup and a
Horner sum, with derivatives by autodiff of the spline.

Coordinates. The inverse is stored as g(s) = ln t on knots uniform in s = ln y, for y =
fun(t) with t > 0. Curves that behave as powers of t at both ends (the rough sphere:
t^(7/3) at its contact edge, t at large approach) make g asymptotically linear in s, so
a quintic spline converges fast and linear extrapolation beyond the knots (C1, the end
value and slope) follows the power law there; callers with a better asymptotic form
replace the value above the top themselves.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.safe_math import graded_cell, horner_rows

__all__ = ["solve_increasing", "build", "evaluate"]

_NEWTON_STEPS = 40
_NEWTON_TOL = 1e-15   # relative step (to 1 + |x|) below which Newton has converged


def _slope(fun, x):
    return jax.jvp(fun, (x,), (jnp.ones_like(x),))


def _positive(x):
    return jnp.maximum(x, jnp.finfo(jnp.result_type(x)).tiny)


@partial(jax.custom_jvp, nondiff_argnums=(0, 3))
def solve_increasing(fun: Callable, target: ArrayLike, start: ArrayLike,
                     floor: float) -> jnp.ndarray:
    """x with fun(x) = target, for fun increasing and convex on (floor, inf): Newton from
    ``start`` to convergence, never stepping more than halfway to ``floor``; elementwise.
    Implicit-function derivative (custom_jvp), not the iterations'."""
    def body(state):
        k, x, _ = state
        val, der = _slope(fun, x)
        new = jnp.maximum(x - (val - target) / _positive(der), 0.5 * (x + floor))
        return k + 1, new, jnp.max(jnp.abs(new - x) / (1.0 + jnp.abs(new)), initial=0.0)

    def more(state):
        k, _, change = state
        return (k < _NEWTON_STEPS) & (change > _NEWTON_TOL)

    start = jnp.asarray(start, float)
    return jax.lax.while_loop(more, body, (0, start, jnp.inf))[1]


@solve_increasing.defjvp
def _solve_increasing_jvp(fun, floor, primals, tangents):
    target, start = primals
    x = solve_increasing(fun, target, start, floor)
    der = _slope(fun, x)[1]
    return x, tangents[0] / _positive(der)


def build(log_t_of: Callable[[np.ndarray], np.ndarray], s_lo: float, s_hi: float,
          n_knots: int) -> dict[str, np.ndarray]:
    """Table of g(s) = ln t on ``n_knots`` knots uniform in s in [s_lo, s_hi];
    ``log_t_of(s)`` is the exact inverse (e.g. :func:`solve_increasing`) at an array of s.
    Quintic spline (scipy make_interp_spline, k = 5: C4), stored as local Taylor
    coefficients per cell, highest power first."""
    from scipy.interpolate import make_interp_spline

    s = np.linspace(s_lo, s_hi, n_knots)
    g = np.asarray(log_t_of(s), float)
    if not np.all(np.isfinite(g)) or np.any(np.diff(g) <= 0):
        raise ValueError("the inverse is not finite and increasing on the knots")
    spline = make_interp_spline(s, g, k=5)
    coef = np.stack([spline(s[:-1], nu=k) / math.factorial(k) for k in range(5, -1, -1)])
    return {"s_range": np.asarray([s_lo, s_hi]), "coef": coef,
            "end_slopes": np.asarray([spline(s_lo, nu=1), spline(s_hi, nu=1)]),
            "end_values": np.asarray([g[0], g[-1]])}


def evaluate(table: dict[str, np.ndarray], s: ArrayLike) -> jnp.ndarray:
    """g(s) = ln t from ``table`` (:func:`build`) at any real s: the spline on its range,
    linear (C1) beyond it. Differentiable everywhere; only the clamped s reaches the
    spline, so gradients stay finite."""
    s = jnp.asarray(s, float)
    lo, hi = (float(v) for v in table["s_range"])
    n = int(np.shape(table["coef"])[1])
    h = (hi - lo) / n
    sc = jnp.where(s < lo, lo, jnp.where(s > hi, hi, s))
    i, ds = graded_cell(sc, (sc - lo) / h, lambda j: lo + h * j, n)
    y = horner_rows(np.ascontiguousarray(np.asarray(table["coef"]).T), i, ds)
    (g_lo, g_hi), (d_lo, d_hi) = table["end_values"], table["end_slopes"]
    return jnp.where(s < lo, float(g_lo) + float(d_lo) * (s - lo),
                     jnp.where(s > hi, float(g_hi) + float(d_hi) * (s - hi), y))
