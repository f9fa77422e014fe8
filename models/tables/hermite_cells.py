"""Evaluation of a backbone surrogate on cells in p: its Chebyshev interpolant resampled as
cubic Hermite pieces, for tables whose shape parameter differs from point to point.

Why. A surrogate (:mod:`models.tables.surrogate`) is a cubic spline in the amplitude coordinate,
tensor product with a Chebyshev interpolant in p of up to 24 terms. Where p is one number
for all sweep points (Hertz, the power law) the Chebyshev sums are taken once per knot. A
law whose p differs per protocol (the rough sphere's D0' = delta0'/sigma) needs them per
point: each point then gathers 4 x 24 coefficients for its cell and sums them, which on
the CPU is memory traffic (454 points x 96 coefficients, 350 kB per evaluation) and most
of the likelihood's cost. On cells in p, a point gathers 4 x 4.

Construction (deterministic, from the stored table, on first use). Each piece
[p_k, p_k+1] of the table is cut into ``p_cells[k]`` equal cells; on each cell every
spline coefficient and x_c(p) are the cubic Hermite interpolants of the Chebyshev
interpolant's values and p-derivatives at the cell ends (exact derivatives of the
Chebyshev series). The result is C1 in p inside a piece, continuous to the table's error at
a break, as the interpolant is. Its error against the Chebyshev interpolant is at most
h^4/384 max|d^4 S/dp^4| per cell of width h; the tests measure it (the rough sphere:
below 1e-6 in Delta f/f0, against the table's stated 3e-5).
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from numpy.polynomial import chebyshev as cheb

from beadrod.models.safe_math import graded_cell, materialize

__all__ = ["both_regions", "resample", "evaluate", "amplitude_cell", "cubic",
           "contact_knot", "flight_knot", "hermite",
           "cubic_slope", "value_and_tangent"]

_KEY = "_p_cells_resampled"   # where the resampled arrays are kept, in the loaded table


def both_regions(table: dict[str, np.ndarray]) -> np.ndarray:
    """The contact cells' coefficients, then the flight cells' (the cells' axis: -2, or -3
    in a table with a second shape coordinate, whose last axis is its Chebyshev terms)."""
    axis = -3 if "q_range" in table else -2
    return np.concatenate([table["coef_contact"], table["coef_flight"]], axis=axis)


def contact_knot(s):
    """Contact-region knot u [-] at fractional position s in [0, 1]: 1 - (1 - s)^2 (graded
    towards the kink u = 1). One definition for the builder and the lookup."""
    return 1.0 - (1.0 - s) ** 2


def flight_knot(s):
    """Flight-region knot v [-] at fractional position s in [0, 1]: s^2 (graded towards
    the kink v = 0)."""
    return s**2


def hermite(f0, f1, d0, d1, h):
    """Cubic Hermite piece on [0, h] from end values f0, f1 and slopes d0, d1: its power
    coefficients in the offset from 0, highest first, stacked on a new last axis."""
    s = (f1 - f0) / h
    return np.stack([(d0 + d1 - 2.0 * s) / h**2, (3.0 * s - 2.0 * d0 - d1) / h, d0, f0], -1)


def _hermite(values: np.ndarray, slopes: np.ndarray, h: float) -> np.ndarray:
    # cells along axis 0 (n + 1 nodes -> n cells)
    return hermite(values[:-1], values[1:], slopes[:-1], slopes[1:], h)


def resample(table: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The Hermite cells of ``table`` (its 'p_cells': cells per piece), computed once and
    kept in the table dict."""
    if _KEY in table:
        return table[_KEY]
    edges = np.asarray(table.get("p_edges", table["p_range"]), float)
    counts = np.asarray(table["p_cells"], int).reshape(-1)
    if counts.size != edges.size - 1 or np.any(counts < 1):
        raise ValueError(f"p_cells {counts.tolist()}: one count >= 1 per piece "
                         f"({edges.size - 1})")
    coef, xcc = both_regions(table), np.asarray(table["xc_cheb"])
    if "p_edges" not in table:
        coef, xcc = coef[None], xcc[None]
    cells, xcs = [], []
    for k, n in enumerate(counts):
        lo, hi = edges[k], edges[k + 1]
        nu = np.linspace(-1.0, 1.0, n + 1)
        h = (hi - lo) / n
        for a, out in ((coef[k], cells), (xcc[k], xcs)):
            c = np.moveaxis(a, -1, 0)                          # Chebyshev index first
            v = np.moveaxis(cheb.chebval(nu, c), -1, 0)        # (n + 1, ...)
            d = np.moveaxis(cheb.chebval(nu, cheb.chebder(c)), -1, 0) * 2.0 / (hi - lo)
            out.append(_hermite(v, d, h))
    # (cells, 4 u-powers, knots, 4 p-powers) -> (cells, knots, 4 u-powers, 4 p-powers):
    # one point's 16 coefficients contiguous
    res = {"coef": np.ascontiguousarray(np.transpose(np.concatenate(cells), (0, 2, 1, 3))),
           "xc": np.concatenate(xcs), "lo": edges[:-1],
           "width": (edges[1:] - edges[:-1]) / counts, "offset": np.cumsum(counts) - counts,
           "count": counts, "breaks": edges[1:-1]}
    table[_KEY] = res
    return res


def evaluate(table: dict[str, np.ndarray], xs: jnp.ndarray, ps: jnp.ndarray,
             prefactor: Callable[[jnp.ndarray], jnp.ndarray] | None = None) -> jnp.ndarray:
    """S(x, p) on the Hermite cells, xs in [0, x_max] and ps in the table's range (clamped
    by the caller) [-]; broadcast together, the cell in p is found at ps's own shape.
    Derivatives by hand (:func:`value_and_tangent`)."""
    r = resample(table)
    xs, ps = jnp.asarray(xs, float), jnp.asarray(ps, float)
    pre = jnp.asarray(1.0 if prefactor is None else prefactor(ps), float)
    x_max = float(table["x_max"])

    def locate(ps):
        k = sum((ps >= b).astype(jnp.int32) for b in r["breaks"]) + jnp.zeros(ps.shape,
                                                                             jnp.int32)
        lo, width = jnp.asarray(r["lo"])[k], jnp.asarray(r["width"])[k]
        j = jnp.clip(jnp.floor((ps - lo) / width).astype(jnp.int32), 0,
                     jnp.asarray(r["count"])[k] - 1)
        return ps - (lo + j * width), materialize(jnp.asarray(r["offset"])[k] + j)

    # coef and xcc are arguments, not closed over (see models.tables.one_shape.evaluate)
    @jax.custom_jvp
    def f(xs, ps, pre, coef, xcc):
        dp, cell = locate(ps)
        inside, i, d = amplitude_cell(table, xs, cubic(xcc[cell], dp))
        y = cubic(cubic(coef[cell, materialize(i)], dp[..., None]), d)
        return jnp.where(inside, pre * xs * xs * y, y)

    @f.defjvp
    def f_jvp(primals, tangents):
        xs, ps, pre, coef, xcc = primals
        txs, tps, tpre = tangents[:3]     # the table's constants have none
        dp, cell = locate(ps)
        a = xcc[cell]
        xc, dxc = cubic(a, dp), cubic_slope(a, dp)
        inside, i, d = amplitude_cell(table, xs, xc)
        g = coef[cell, materialize(i)]                  # (..., 4 u-powers, 4 p-powers)
        e = dp[..., None]
        return value_and_tangent(inside, xs, d, xc, dxc, cubic(g, e), cubic_slope(g, e),
                                 pre, x_max, txs, tps, tpre)

    return f(xs, ps, pre, jnp.asarray(r["coef"]), jnp.asarray(r["xc"]))


def _check_grading(knots: np.ndarray, grade: Callable[[np.ndarray], np.ndarray],
                   what: str) -> None:
    s = np.linspace(0.0, 1.0, knots.size)
    if not np.allclose(knots, grade(s), rtol=0.0, atol=1e-14):
        raise ValueError(f"the table's {what} are not graded as models.tables.surrogate builds "
                         "them; rebuild the table")


def amplitude_cell(table: dict[str, np.ndarray], xs: jnp.ndarray,
                   xc: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """(inside, cell, offset) of amplitude xs [-] in ``table``'s spline cells, the contact
    cells (u = x/x_c, inside = x <= x_c) first and the flight cells (v = (x - x_c)/(x_max -
    x_c)) after them, as :func:`both_regions` stores them, so one gather reads either.

    The knots are located from their grading's closed form (:func:`contact_knot`,
    :func:`flight_knot`, checked against the stored knots), not read from the knot arrays
    (:func:`models.safe_math.graded_cell`: a gather from a knot array costs more)."""
    x_max = float(table["x_max"])
    uk, vk = np.asarray(table["u_knots"]), np.asarray(table["v_knots"])
    _check_grading(uk, contact_knot, "u knots")
    _check_grading(vk, flight_knot, "v knots")
    ku, kv = uk.size - 1, vk.size - 1
    u = xs / xc
    v = (xs - xc) / (x_max - xc)
    iu, du = graded_cell(u, ku * (1.0 - jnp.sqrt(jnp.clip(1.0 - u, 0.0, 1.0))),
                         lambda i: contact_knot(i / ku), ku)
    iv, dv = graded_cell(v, kv * jnp.sqrt(jnp.clip(v, 0.0, 1.0)), lambda i: flight_knot(i / kv),
                         kv)
    inside = xs <= xc
    return inside, jnp.where(inside, iu, iv + ku), jnp.where(inside, du, dv)


def cubic(c: jnp.ndarray, d: jnp.ndarray) -> jnp.ndarray:
    """c0 d^3 + c1 d^2 + c2 d + c3, the 4 coefficients on the last axis of c."""
    return ((c[..., 0] * d + c[..., 1]) * d + c[..., 2]) * d + c[..., 3]


def cubic_slope(c: jnp.ndarray, d: jnp.ndarray) -> jnp.ndarray:
    """d/dd of :func:`cubic`: 3 c0 d^2 + 2 c1 d + c2."""
    return (3.0 * c[..., 0] * d + 2.0 * c[..., 1]) * d + c[..., 2]


def value_and_tangent(inside, xs, d, xc, dxc, c, dc, pre, x_max, txs, tp, tpre):
    """(F, dF) of F = pre x^2 y(d) in contact (inside), y(d) in flight, with d the offset
    of u = x/x_c (contact) or v = (x - x_c)/(x_max - x_c) (flight) in its cell, c the
    cell's coefficients and dc their derivative in the shape coordinate p, dxc = dx_c/dp;
    dF = F_x txs + F_p tp + F_pre tpre. With y_d the cubic's slope and y_p the cubic of dc:

        contact: F_x = pre (2 x y + x^2 y_d / x_c),
                 F_p = pre x^2 (y_p - y_d x x_c' / x_c^2);
        flight:  F_x = y_d / (x_max - x_c),
                 F_p = y_p + y_d (x - x_max) x_c' / (x_max - x_c)^2.

    A table with two shape coordinates passes ``dxc``, ``dc`` and ``tp`` as tuples, one
    entry each (F_p for each, each times its tangent). Written out because autodiff of
    the lookup re-derives the cell search inside several reductions (and, at one p for
    all points, scatters into the knot array): on the CPU that costs two to three times
    the value (:mod:`models.tables.one_shape`). Why the partials are formed from the primal
    coefficients and only then multiplied by the tangents: the reverse pass is then one
    product and sum per coordinate (a per-point coefficient tangent, dc times tp formed
    first, costs more: models.tables.patches_2d).
    """
    y, y_d = cubic(c, d), cubic_slope(c, d)
    span = x_max - xc
    x2y = xs * xs * y
    f_x = jnp.where(inside, pre * (2.0 * xs * y + xs * xs * y_d / xc), y_d / span)
    tangent = f_x * txs + jnp.where(inside, x2y, 0.0) * tpre
    as_tuple = lambda v: v if isinstance(v, tuple) else (v,)  # noqa: E731
    for a, b, t in zip(as_tuple(dxc), as_tuple(dc), as_tuple(tp)):
        y_p = cubic(b, d)
        f_p = jnp.where(inside, pre * xs * xs * (y_p - y_d * xs * a / (xc * xc)),
                        y_p + y_d * (xs - x_max) * a / (span * span))
        tangent = tangent + f_p * t
    return jnp.where(inside, pre * x2y, y), tangent
