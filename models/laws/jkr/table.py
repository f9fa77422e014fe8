"""Tabulated JKR first-order shift, fast enough for NUTS and nested sampling.

:func:`shift_first_order_fast` reproduces :func:`models.laws.jkr.contact.shift_first_order` (the
averaged tangent stiffness of the JKR unloading branch, K clipped to 0 where the overlap
is <= 0) from a table computed once by that quadrature and stored in
``models/laws/jkr/data/jkr_table.npz``.

Why a two-parameter table is exact in structure. JKR has one length scale per
stiffness, L = (pi gamma R^2/E*)^(1/3): with a = L s^2 and delta = (L^2/R)(s^4 - 2s) the
force is F = (pi gamma R) f(s) with f depending on s alone (Maugis' dimensionless
form). At a given load F0 the state s0 therefore depends on the single ratio
r = F0/Fc (Fc = 3 pi gamma R, the load-controlled pull-off force), and

    Delta f/f0 = <K(delta0 (1 + x sin t))>/(2 K0) - 1/2

is a function of (x, r) alone: E* only rescales lengths and stiffnesses (the tests check
the invariance to 1e-15 and the table against the quadrature at random points).

Method. Coordinates: x in [0, 1] (in contact throughout the cycle) and w = sqrt(x - 1)
in [0, sqrt(X_MAX - 1)] past x = 1, where the stiffness K(0+) > 0 of JKR switches off
inside the cycle and the shift gains a term ~ -(x - 1)^(1/2) (smooth in w); and
q = ln r in [ln R_MIN, ln R_MAX]. In each region a tensor-product cubic spline
(not-a-knot, scipy.interpolate.CubicSpline along x, then along q) on knots graded
quadratically towards x = 1. Samples: models.laws.jkr.contact.shift_first_order (tanh-sinh,
81 nodes; the mechanics, not the law module models.laws.jkr, which imports this table).
Beyond the q range the value is held at the end (r > R_MAX is Hertz to within the
measured 1e-5 at x = 1; r < R_MIN means gamma beyond any steel); beyond X_MAX it is held
too (callers clip); x < 0 uses |x| (the shift is even in the amplitude).

Regenerate (deterministic)::

    python -m beadrod.models.laws.jkr.table --rebuild
"""

from __future__ import annotations

import pathlib

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.laws.jkr.contact import shift_first_order
from beadrod.models.safe_math import knot_cell
from beadrod.models.tables.rebuild import rebuild_cli
from beadrod.models.tables.surrogate import X_MAX

__all__ = ["X_MAX", "R_MIN", "R_MAX", "TABLE_PATH", "load_ratio", "shift_first_order_fast",
           "build_table", "load_table", "reference_shift"]

R_MIN, R_MAX = 1e-3, 1e6
TABLE_PATH = pathlib.Path(__file__).with_name("data") / "jkr_table.npz"

_NX_CONTACT = 96
_NX_FLIGHT = 48
_NQ = 72

_TABLE: dict[str, np.ndarray] | None = None


def load_ratio(load: ArrayLike, *, gamma: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """r = F0/Fc = F0/(3 pi gamma R) [-], the one parameter of the JKR shift curve."""
    return jnp.asarray(load, float) / (3.0 * jnp.pi * jnp.asarray(gamma, float)
                                       * jnp.asarray(radius, float))


def reference_shift(x: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The quadrature the table reproduces, at load 1 N, R = 1 cm, E* = 100 GPa."""
    radius = 0.01
    gamma = 1.0 / (3.0 * np.pi * np.asarray(r) * radius)
    return np.asarray(shift_first_order(jnp.asarray(x), load=1.0, e_star=1e11, radius=radius,
                                        gamma=jnp.asarray(gamma)))


def _grids() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    s = np.linspace(0.0, 1.0, _NX_CONTACT)
    xk = 1.0 - (1.0 - s) ** 2                                     # dense towards x = 1
    wk = np.sqrt(X_MAX - 1.0) * np.linspace(0.0, 1.0, _NX_FLIGHT) ** 1.5
    qk = np.linspace(np.log(R_MIN), np.log(R_MAX), _NQ)
    return xk, wk, qk


def _tensor_spline(zk: np.ndarray, qk: np.ndarray, values: np.ndarray) -> np.ndarray:
    """values (nz, nq) -> local coefficients (4, nq-1, 4, nz-1): c[b, j, a, i] multiplies
    dq^(3-b) dz^(3-a) in cell (i, j)."""
    from scipy.interpolate import CubicSpline

    cz = CubicSpline(zk, values, axis=0).c                        # (4, nz-1, nq)
    return CubicSpline(qk, cz, axis=2).c                          # (4, nq-1, 4, nz-1)


def build_table() -> dict[str, np.ndarray]:
    """Evaluate the quadrature on the grid and fit the splines (deterministic)."""
    xk, wk, qk = _grids()
    r = np.exp(qk)
    xx, rr = np.meshgrid(xk, r, indexing="ij")
    contact = reference_shift(xx.ravel(), rr.ravel()).reshape(xx.shape)
    ww, rr = np.meshgrid(wk, r, indexing="ij")
    flight = reference_shift(1.0 + ww.ravel() ** 2, rr.ravel()).reshape(ww.shape)
    return {"x_knots": xk, "w_knots": wk, "q_knots": qk,
            "coef_contact": _tensor_spline(xk, qk, contact),
            "coef_flight": _tensor_spline(wk, qk, flight),
            "x_max": np.asarray(X_MAX)}


def load_table() -> dict[str, np.ndarray]:
    """The stored table as numpy arrays (loaded once; no JAX arrays at import time)."""
    global _TABLE
    if _TABLE is None:
        with np.load(TABLE_PATH) as f:
            _TABLE = {k: f[k] for k in f.files}
    return _TABLE


def _eval(zk, qk, coef, z, q, fz):
    # fz: z's fractional knot index (closed form of the grading in _grids)
    i, dz = knot_cell(zk, z, fz)
    j, dq = knot_cell(qk, q, (q - qk[0]) / (qk[1] - qk[0]))
    if q.ndim == 0:
        # one ratio, many x (the sampler's case): reduce to a 1-D spline in z first
        # (Horner in dq on the ratio's block), then four 1-D gathers per point and Horner
        # in dz: no einsum or 2-D gather, which under vmap over particles cost more on the
        # CPU
        blk = jax.lax.dynamic_index_in_dim(jnp.asarray(coef), j, axis=1, keepdims=False)
        cz = ((blk[0] * dq + blk[1]) * dq + blk[2]) * dq + blk[3]
        return ((cz[0][i] * dz + cz[1][i]) * dz + cz[2][i]) * dz + cz[3][i]
    pz = jnp.stack([dz**3, dz**2, dz, jnp.ones_like(dz)], axis=-1)
    pq = jnp.stack([dq**3, dq**2, dq, jnp.ones_like(dq)], axis=-1)
    # advanced indices separated by a slice go first: (..., 4, 4) as [b, a]
    c = jnp.asarray(coef)[:, j, :, i]
    return jnp.einsum("...ba,...b,...a->...", c, pq, pz)


@jax.jit
def shift_first_order_fast(x: ArrayLike, ratio: ArrayLike) -> jnp.ndarray:
    """JKR first-order Delta f/f0 [-] at x = delta_a/delta0 (delta0 the JKR static overlap)
    and load ratio r = F0/Fc (:func:`load_ratio`); broadcasting.

    Equals models.laws.jkr.shift_first_order(x, load=F0, e_star=any, radius=R, gamma) with
    r = F0/(3 pi gamma R), to within the error measured in tests/test_jkr_table.py.
    Differentiable in x and r (C2 in x except at x = 1, where the exact curve has a
    one-sided (x - 1)^(1/2) term and the table is C0 with a finite one-sided slope).
    """
    tab = load_table()
    x, r = jnp.asarray(x, float), jnp.asarray(ratio, float)
    if r.ndim > 0:  # a scalar ratio stays scalar: see _eval
        x, r = jnp.broadcast_arrays(x, r)
    xs = jnp.clip(jnp.abs(x), 0.0, X_MAX)
    q = jnp.clip(jnp.log(jnp.maximum(r, R_MIN)), np.log(R_MIN), np.log(R_MAX))
    # double where: the flight coordinate sqrt(x - 1) sees x >= 1 only
    w = jnp.sqrt(jnp.where(xs > 1.0, xs - 1.0, 0.0))
    xk = jnp.minimum(xs, 1.0)
    last_x, last_w = tab["x_knots"].size - 1, tab["w_knots"].size - 1
    fx = last_x * (1.0 - jnp.sqrt(1.0 - xk))
    fw = last_w * jnp.cbrt(jnp.square(w / np.sqrt(X_MAX - 1.0)))
    contact = _eval(tab["x_knots"], tab["q_knots"], tab["coef_contact"], xk, q, fx)
    flight = _eval(tab["w_knots"], tab["q_knots"], tab["coef_flight"], w, q, fw)
    return jnp.where(xs > 1.0, flight, contact)


def _main(argv: list[str] | None = None) -> int:
    return rebuild_cli(argv, prog="python -m beadrod.models.laws.jkr.table",
                       description="Tabulated JKR first-order shift.",
                       build=build_table, path=TABLE_PATH)


if __name__ == "__main__":
    raise SystemExit(_main())
