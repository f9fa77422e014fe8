"""Private numerical helpers: NaN-safe powers, roots and branches.

Every physics module imports these instead of writing its own guards. The idiom
is the double ``where``: the unsafe branch is fed a harmless dummy argument, so
both the value *and* the gradient stay finite where the branch is not taken.
"""

from __future__ import annotations

from collections.abc import Callable

import jax.numpy as jnp
from jax.typing import ArrayLike

__all__ = ["safe_pow", "safe_sqrt", "pos_pow", "safe_log", "smooth_relu", "knot_cell",
           "graded_cell", "horner_rows", "materialize"]


def safe_sqrt(x: ArrayLike) -> jnp.ndarray:
    """sqrt(x) for x > 0, 0 for x <= 0, with a zero (not NaN/inf) gradient at x <= 0."""
    x = jnp.asarray(x)
    pos = x > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, x, 1.0)), 0.0)


def safe_pow(x: ArrayLike, p: ArrayLike) -> jnp.ndarray:
    """x**p for x > 0, 0 for x <= 0 (the unilateral-contact clip), NaN-free gradients.

    The gradient at x = 0 with p < 1 diverges in truth; here it is reported as 0,
    the one-sided value from the open (x < 0) side. Callers that need the true
    behaviour at the contact edge must not rely on it.
    """
    x = jnp.asarray(x)
    pos = x > 0
    return jnp.where(pos, jnp.power(jnp.where(pos, x, 1.0), p), 0.0)


pos_pow = safe_pow


def safe_log(x: ArrayLike, tiny: float = 1e-300) -> jnp.ndarray:
    """log(max(x, tiny)) with a finite gradient everywhere."""
    x = jnp.asarray(x)
    ok = x > tiny
    return jnp.where(ok, jnp.log(jnp.where(ok, x, 1.0)), jnp.log(tiny))


def smooth_relu(x: ArrayLike, width: ArrayLike) -> jnp.ndarray:
    """Softplus of width ``width``: a C-infinity stand-in for max(x, 0)."""
    x = jnp.asarray(x)
    return width * jnp.logaddexp(0.0, x / width)


def knot_cell(knots: ArrayLike, z: ArrayLike, frac: ArrayLike) -> tuple[jnp.ndarray,
                                                                          jnp.ndarray]:
    """(i, z - knots[i]) with knots[i] <= z < knots[i+1], clipped to the end pieces.

    ``frac`` is the fractional index of z from the closed form of the knot grading
    (e.g. k (1 - sqrt(1 - u)) for u_i = 1 - (1 - i/k)^2); one comparison each way
    repairs rounding at a knot. Not jnp.searchsorted: its binary search costs far more
    per point under vmap on the CPU.
    """
    knots = jnp.asarray(knots)
    last = knots.shape[0] - 2
    i = jnp.clip(jnp.floor(jnp.nan_to_num(frac)).astype(jnp.int32), 0, last)
    i = jnp.where((z < knots[i]) & (i > 0), i - 1, i)
    i = jnp.where((z >= knots[jnp.minimum(i + 1, last + 1)]) & (i < last), i + 1, i)
    return i, z - knots[i]


def graded_cell(z: ArrayLike, frac: ArrayLike, knot: Callable[[jnp.ndarray], jnp.ndarray],
                n_cells: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(i, z - knot(i)) for knots given by a closed form: i = floor(frac) clipped to
    [0, n_cells - 1], ``frac`` the fractional index of z and ``knot(i)`` [same unit as z]
    the knot at (float) index i, e.g. 1 - (1 - i/k)^2 for a grading towards 1.

    Why not :func:`knot_cell`: on the CPU each per-point gather from a knot array costs
    about as much as the rest of a cubic lookup (3 of them per grid); the closed form
    costs a few flops. No rounding repair is needed: a point
    that rounding puts in the neighbouring cell is evaluated ~1e-16 outside it, where a
    spline continuous across its knots has the same value to rounding.
    """
    i = jnp.clip(jnp.floor(jnp.nan_to_num(jnp.asarray(frac))), 0, n_cells - 1)
    return i.astype(jnp.int32), jnp.asarray(z) - knot(i)


def horner_rows(rows: ArrayLike, index: ArrayLike, d: ArrayLike) -> jnp.ndarray:
    """sum_k rows[index, k] d^(K-1-k): the local polynomial of cell ``index`` at offset d.

    ``rows`` (cells, K) holds each cell's power coefficients, highest first, contiguous:
    one gather reads a point's K coefficients. A (K, cells) layout would gather K times,
    once per strided row.
    """
    c = jnp.asarray(rows)[materialize(index)]
    y = c[..., 0]
    for k in range(1, c.shape[-1]):
        y = y * d + c[..., k]
    return y


def materialize(index: ArrayLike) -> jnp.ndarray:
    """``index`` (an integer array) unchanged, computed once before the gather that uses it.

    Why: XLA fuses an index's elementwise producers into the gather that consumes it and
    then recomputes them for every gathered element; a table lookup that gathers 4 x 24
    coefficients per point repeated its whole cell search (and the Chebyshev basis the
    search depends on) 96 times. A reduction is a fusion boundary XLA keeps (it removes
    ``jax.lax.optimization_barrier`` on the CPU), so the index is summed with zeros along a
    new axis of length 2.
    """
    index = jnp.asarray(index)
    return jnp.sum(jnp.stack([index, jnp.zeros_like(index)]), axis=0, dtype=index.dtype)
