"""A backbone surrogate evaluated at one shape parameter for every point, with its
derivatives written out.

The sampler's case: a law whose shape parameter p is one number for all sweep points (the
power law's n, the JKR and DMT load ratio, which depend on global parameters only) reads
the table of :mod:`models.tables.surrogate` at many amplitudes x and one p. The Chebyshev sums in
p are then taken once per knot (cells x 4 coefficients), and each point gathers its
cell's 4 and evaluates a cubic.

Why the derivatives are written out (a ``custom_jvp``): reverse-mode autodiff of that
lookup transposes the per-point gather into a scatter-add over the knot array and
re-derives the cell search inside several reductions; on the CPU that costs two to three
times the value. By hand, with
the coefficients' p-derivatives gathered beside them (8 numbers per point), the tangent is
S_x dx + S_nu dnu: elementwise in x, a sum over points in the scalar nu.

The formulas are :func:`models.tables.hermite_cells.value_and_tangent`'s, shared with the per-point
lookup. The tests compare every derivative with those of the autodiff evaluation.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.models.safe_math import materialize
from beadrod.models.tables import chebyshev
from beadrod.models.tables.hermite_cells import amplitude_cell, cubic, value_and_tangent

__all__ = ["evaluate"]


def evaluate(table: dict[str, np.ndarray], rows: jnp.ndarray, xc_cheb: jnp.ndarray,
             xs: jnp.ndarray, nu: jnp.ndarray, pre: jnp.ndarray | float = 1.0) -> jnp.ndarray:
    """F(x, nu) [-]: pre x^2 y in contact, y in flight (module doc), at amplitudes xs in
    [0, x_max], one scalar nu in [-1, 1] (the table piece's coordinate) and one scalar
    prefactor ``pre``.

    ``rows`` (cells, 4, m): the piece's spline coefficients, contact cells then flight
    cells, each cell's 4 powers (highest first) over m Chebyshev terms; ``xc_cheb`` (m,):
    x_c's Chebyshev coefficients. Both are the table's constants (no tangent)."""
    m = int(np.shape(xc_cheb)[-1])
    x_max = float(table["x_max"])

    # rows and xc_cheb are arguments, not closed over: a custom_jvp rule that closes over
    # arrays made inside an enclosing jit sees that trace's stale tracers when linearized
    def kink(t, xc_cheb):
        return t @ xc_cheb

    @jax.custom_jvp
    def f(xs, nu, pre, rows, xc_cheb):
        t = chebyshev.basis(nu, m)
        inside, i, d = amplitude_cell(table, xs, kink(t, xc_cheb))
        y = cubic((rows @ t)[materialize(i)], d)
        return jnp.where(inside, pre * xs * xs * y, y)

    @f.defjvp
    def f_jvp(primals, tangents):
        xs, nu, pre, rows, xc_cheb = primals
        txs, tnu, tpre = tangents[:3]     # the table's constants have none
        t, dt = chebyshev.basis_and_slope(nu, m)
        xc, dxc = kink(t, xc_cheb), kink(dt, xc_cheb)
        inside, i, d = amplitude_cell(table, xs, xc)
        both = (rows @ jnp.stack([t, dt], axis=-1))[materialize(i)]   # (..., 4, 2)
        return value_and_tangent(inside, xs, d, xc, dxc, both[..., 0], both[..., 1], pre,
                                 x_max, txs, tnu, tpre)

    return f(jnp.asarray(xs, float), jnp.asarray(nu, float), jnp.asarray(pre, float),
             jnp.asarray(rows, float), jnp.asarray(xc_cheb, float))
