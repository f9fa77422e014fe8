"""The Chebyshev basis T_0..T_{m-1} of the backbone surrogates, and its derivative.

Why its own module: :mod:`models.tables.surrogate` (building, and evaluation per point) and
:mod:`models.tables.one_shape` (evaluation at one shape parameter, derivative by hand) both
evaluate it, and the second is imported by the first.

Why from the powers of nu and not the three-term recurrence: for one scalar nu (the
sampler's case) the recurrence is ~2m scalar XLA operations, each a separate kernel on
the CPU, and its reverse-mode pass as many again (most of a table lookup's cost); the
powers are one vector operation and their derivative a second. Why not
cos(k arccos nu): its derivative is singular at nu = +-1, where a clamped shape parameter
sits. Rounding: the monomial coefficients of T_k grow like (1 + sqrt 2)^k, so T_k(nu)
carries an absolute error ~1e-16 (1 + sqrt 2)^k (2e-11 at k = 15, 2e-8 at k = 23,
measured against numpy's Clenshaw sum), multiplied by the table's Chebyshev coefficients
of that order, which fall far faster (the tests bound the effect on every stored table).
Above :data:`MAX_TERMS` terms the recurrence is used.
"""

from __future__ import annotations

from functools import cache

import jax
import jax.numpy as jnp
import numpy as np
from numpy.polynomial import chebyshev as cheb

__all__ = ["MAX_TERMS", "basis", "basis_and_slope", "gauss_nodes", "to_chebyshev"]

MAX_TERMS = 24
"""The most terms evaluated from powers (2e-8 absolute rounding in T_23); above, the
three-term recurrence."""


@cache
def _monomial_matrix(m: int) -> np.ndarray:
    # T_k(nu) = sum_j M[k, j] nu^j: integers, exact in float64 at these orders
    rows = [cheb.cheb2poly(np.eye(m)[k]) for k in range(m)]   # trailing zeros trimmed
    return np.stack([np.pad(r, (0, m - r.size)) for r in rows])


@jax.custom_jvp
def _powers(nu: jnp.ndarray, k: jnp.ndarray) -> jnp.ndarray:
    # nu^k for integer-valued k >= 0 (a float array), negative nu included
    odd = jnp.mod(k, 2.0) == 1.0
    return jnp.where(k == 0.0, 1.0, jnp.abs(nu)[..., None] ** k
                     * jnp.where(odd & (nu[..., None] < 0.0), -1.0, 1.0))


@_powers.defjvp
def _powers_jvp(primals, tangents):
    nu, k = primals
    pw = _powers(nu, k)
    # d nu^k / d nu = k nu^(k-1): the next lower power (no 0 * 0^-1 at nu = 0)
    lower = jnp.concatenate([jnp.zeros_like(pw[..., :1]), pw[..., :-1]], axis=-1)
    return pw, k * lower * tangents[0][..., None]


def _recurrence(nu: jnp.ndarray, m: int) -> jnp.ndarray:
    t = [jnp.ones_like(nu), nu]
    for _ in range(m - 2):
        t.append(2.0 * nu * t[-1] - t[-2])
    return jnp.stack(t[:m], axis=-1)


def basis(nu: jnp.ndarray, m: int) -> jnp.ndarray:
    """T_0..T_{m-1}(nu) [-] for nu in [-1, 1], shape nu.shape + (m,); differentiable."""
    nu = jnp.asarray(nu, float)
    if m > MAX_TERMS:
        return _recurrence(nu, m)
    return _powers(nu, jnp.arange(m, dtype=float)) @ jnp.asarray(_monomial_matrix(m)).T


def basis_and_slope(nu: jnp.ndarray, m: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(T_k(nu), dT_k/dnu) [-], each nu.shape + (m,)."""
    nu = jnp.asarray(nu, float)
    return jax.jvp(lambda v: basis(v, m), (nu,), (jnp.ones_like(nu),))


def gauss_nodes(lo: float, hi: float, m: int) -> tuple[np.ndarray, np.ndarray]:
    """The m Chebyshev-Gauss nodes nu_j = cos(pi (j + 1/2)/m) in (-1, 1) and their images
    in [lo, hi] (no node at the ends): where every table of the project is sampled."""
    nu = np.cos(np.pi * (np.arange(m) + 0.5) / m)
    return nu, 0.5 * (lo + hi) + nu * (hi - lo) / 2.0


def to_chebyshev(values: np.ndarray, nu: np.ndarray, axis: int = -1) -> np.ndarray:
    """Values on the Chebyshev-Gauss nodes nu (along ``axis``) -> the coefficients of
    their interpolant, c_k = (2/m) sum_j f(nu_j) T_k(nu_j), c_0 halved (discrete
    orthogonality of T_k on those nodes)."""
    values = np.moveaxis(np.asarray(values, float), axis, -1)
    m = values.shape[-1]
    t = np.cos(np.outer(np.arange(m), np.arccos(nu)))  # T_k(nu_j)
    coef = values @ t.T * (2.0 / m)
    coef[..., 0] /= 2.0
    return np.moveaxis(coef, -1, axis)

