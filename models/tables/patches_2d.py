"""A backbone surrogate with two shape coordinates, read at one (p, q) for every point, on
local Chebyshev patches resampled from its global interpolant.

Why. A table with a second shape coordinate (:mod:`models.tables.surrogate`; Maugis-Dugdale's, in
the load ratio p = ln F0/Fc and q = ln lambda) is a tensor product of m Chebyshev terms in p
and m_q in q for every spline cell's 4 coefficients and for x_c: 16 x 20 x 377 numbers,
0.96 MB. Read at the sampler's one (p, q), every step would contract all of them, value
and both slopes (and XLA's CPU dot with two right-hand columns is slower than two
matrix-vector products). On patches, a step reads one: ``DEGREE + 1`` terms in each
coordinate, 25 x 377 numbers.

Construction (deterministic, from the stored table, on first use, kept in the loaded
table): the table's p range is cut into ``P_PATCHES`` equal intervals of its Chebyshev
coordinate nu, its q range into ``Q_PATCHES`` (a two-coordinate table with pieces in p,
``p_edges``, is refused: none is built, and the piece index would be a traced value
inside the derivative rule); on each patch the global interpolant is evaluated at the
(DEGREE + 1)^2 Chebyshev-Gauss nodes and re-expanded there (interpolation at those nodes:
within a small factor of the best approximation of that degree). The surrogate is then
continuous across a patch edge to the resampling error only (a jump of that size;
gradients stay finite).

Error against the global interpolant, bounded per coordinate from the stored
Maugis-Dugdale table (each spline coefficient's error times the cell's width to its power,
x^2 <= 4 in contact): 1.3e-6 along p, 4.6e-7 along q at these settings (8 x 4 patches of
degree 6: 6.7e-7 and 4.6e-7 but 49 terms a step). The tests measure it on the surrogate's
values: below :data:`ERROR`, against the table's own stated 1e-5.

Derivatives by hand (``custom_jvp``), as :mod:`models.tables.one_shape`: the patch's three
contractions (value, d/dnu, d/dnu_q) are one product of three basis rows with the patch's
coefficients, and the per-point tangent is :func:`models.tables.hermite_cells.value_and_tangent`'s,
with a partial derivative per shape coordinate formed before the tangents enter (a
per-point coefficient tangent would cost more in the reverse pass).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from numpy.polynomial import chebyshev as cheb

from beadrod.models.safe_math import materialize
from beadrod.models.tables import chebyshev
from beadrod.models.tables.hermite_cells import (
    amplitude_cell,
    both_regions,
    cubic,
    value_and_tangent,
)

__all__ = ["P_PATCHES", "Q_PATCHES", "DEGREE", "ERROR", "resample", "evaluate"]

P_PATCHES = 16
"""Patches along p (equal in its Chebyshev coordinate nu)."""
Q_PATCHES = 8
"""Patches along q (equal in nu_q)."""
DEGREE = 4
"""Chebyshev degree of a patch in p and in q."""
ERROR = 2e-6
"""Largest difference [-] in Delta f/f0 between the patches and the global interpolant
they are resampled from (measured by the tests, module doc)."""

_KEY = "_pq_patches"


def resample(table: dict[str, np.ndarray]) -> np.ndarray:
    """The patches of ``table``: (P_PATCHES x Q_PATCHES, (DEGREE + 1)^2, K + 1), the
    patch's tensor Chebyshev coefficients (p index major), then K = 4 x cells spline
    coefficients and x_c; computed once and kept in the table dict."""
    if _KEY in table:
        return table[_KEY]
    if "p_edges" in table:
        raise ValueError("a table with a second shape coordinate and pieces in p "
                         "(p_edges) has no patches: build it without p_breaks")
    coef = np.swapaxes(both_regions(table), -4, -3)        # (cells, 4, m, m_q)
    xcc = np.asarray(table["xc_cheb"])                       # (m, m_q)
    m, m_q = xcc.shape
    glob = np.concatenate([coef.reshape(-1, m, m_q), xcc[None]])          # (K+1, m, m_q)
    n = DEGREE + 1
    g = chebyshev.gauss_nodes(-1.0, 1.0, n)[0]               # local Chebyshev-Gauss nodes
    out = []
    for i in range(P_PATCHES):
        vp = cheb.chebvander(-1.0 + (2 * i + 1 + g) / P_PATCHES, m - 1)          # (n, m)
        for j in range(Q_PATCHES):
            vq = cheb.chebvander(-1.0 + (2 * j + 1 + g) / Q_PATCHES, m_q - 1)
            vals = np.einsum("kab,ia,jb->kij", glob, vp, vq)
            local = chebyshev.to_chebyshev(chebyshev.to_chebyshev(vals, g, axis=1), g, axis=2)
            out.append(local.reshape(glob.shape[0], n * n))
    table[_KEY] = np.ascontiguousarray(np.swapaxes(np.stack(out), 1, 2))
    return table[_KEY]


def _locate(nu, patches: int):
    # (patch index, local coordinate in [-1, 1]); nu is clamped to [-1, 1] by the caller
    s = (nu + 1.0) * (0.5 * patches)
    i = jnp.clip(jnp.floor(s).astype(jnp.int32), 0, patches - 1)
    return i, 2.0 * (s - i) - 1.0


def evaluate(table: dict[str, np.ndarray], xs: jnp.ndarray, nu: jnp.ndarray,
             nu_q: jnp.ndarray, pre: jnp.ndarray | float = 1.0) -> jnp.ndarray:
    """F(x, nu, nu_q) [-]: pre x^2 y in contact, y in flight (:mod:`models.tables.surrogate`), at
    amplitudes xs in [0, x_max] and one scalar (nu, nu_q) in [-1, 1]^2, the table's
    Chebyshev coordinates."""
    patches = resample(table)
    n = DEGREE + 1
    x_max = float(table["x_max"])

    def coefficients(nu, nu_q, coef, slopes: bool):
        ip, a = _locate(nu, P_PATCHES)
        iq, b = _locate(nu_q, Q_PATCHES)
        k = materialize(ip * Q_PATCHES + iq)
        c = jax.lax.dynamic_index_in_dim(coef, k, 0, keepdims=False)        # (n*n, K+1)
        if not slopes:
            return jnp.outer(chebyshev.basis(a, n), chebyshev.basis(b, n)).ravel() @ c
        ta, da = chebyshev.basis_and_slope(a, n)
        tb, db = chebyshev.basis_and_slope(b, n)
        # d a/d nu = P_PATCHES, d b/d nu_q = Q_PATCHES; the three rows in one product
        # with the patch stored (n*n, K+1): cheaper than three products with it stored
        # (K+1, n*n), the slice's copy included
        rows = jnp.stack([jnp.outer(ta, tb).ravel(), P_PATCHES * jnp.outer(da, tb).ravel(),
                          Q_PATCHES * jnp.outer(ta, db).ravel()])
        return tuple(rows @ c)

    # the patches are an argument, not closed over (see models.tables.one_shape.evaluate)
    @jax.custom_jvp
    def f(xs, nu, nu_q, pre, coef):
        c = coefficients(nu, nu_q, coef, slopes=False)
        inside, i, d = amplitude_cell(table, xs, c[-1])
        y = cubic(c[:-1].reshape(-1, 4)[materialize(i)], d)
        return jnp.where(inside, pre * xs * xs * y, y)

    @f.defjvp
    def f_jvp(primals, tangents):
        xs, nu, nu_q, pre, coef = primals
        txs, tnu, tnu_q, tpre = tangents[:4]     # the table's constants have none
        c, c_p, c_q = coefficients(nu, nu_q, coef, slopes=True)
        xc = c[-1]
        inside, i, d = amplitude_cell(table, xs, xc)
        # one gather of the three (primal) coefficient sets; the tangents enter after it,
        # so that the values stay computable without them (linearization)
        g = jnp.stack([c[:-1], c_p[:-1], c_q[:-1]], -1).reshape(-1, 4, 3)[materialize(i)]
        return value_and_tangent(inside, xs, d, xc, (c_p[-1], c_q[-1]), g[..., 0],
                                 (g[..., 1], g[..., 2]), pre, x_max, txs, (tnu, tnu_q), tpre)

    return f(jnp.asarray(xs, float), jnp.asarray(nu, float), jnp.asarray(nu_q, float),
             jnp.asarray(pre, float), jnp.asarray(patches))
