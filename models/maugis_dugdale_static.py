"""The Maugis-Dugdale static state under the load, tabulated: the sampler's overlap maps.

Why. At a load F0 > 0 the reduced state of a Maugis-Dugdale contact (module
:mod:`models.maugis_dugdale`) follows from two numbers, the load ratio r = F0/Fc (Fc =
-Pbar_c(lam) pi w R, the load-controlled pull-off force) and Maugis' lam: theta0 =
theta(Pbar0, lam) with Pbar0 = F0/(pi w R) = -r Pbar_c(lam). The exact maps need two
bracketed root solves (pull-off angle, then the load's angle; 120 Newton steps), hundreds
of microseconds inside a sampler's step. Tabulated here, as Chebyshev interpolants:

    Pbar_c(lam)                                  [-]  (pull-off, -2 .. -3/2),
    ln n(r, lam),     n = Delta0 k0 / Pbar0      [-]  (delta0 = n F0/(m omega0^2)),
    ln D(r, lam),     D = Delta0 / Pbar0^(2/3)   [-]  (delta0 = d_s Delta0),

k0 = dPbar/dDelta at the state. n is the law's "effective exponent" (3/2 for Hertz, which
both n and D reach as r -> inf); the f0 -> overlap map of :mod:`models.maugis_dugdale`
(the elastic scale scatters, not the adhesion) is delta0 = n F0/(m omega0^2) exactly.

Grid: ln r in [ln 0.3, ln 1000] (the backbone table's range) in two pieces split at ln 10,
ln lam in [ln 0.1, ln 100] (the prior's range) in three split at ln lam = -1 and 1 (the
DMT-JKR transition, where one interpolant converged slowly), 24 x 24 Chebyshev terms per
piece; Pbar_c in the same three pieces of ln lam. Measured against the root solves at
random points (tests/test_maugis_dugdale_static.py): all three within 1e-13 (3e-14 at
2000 points). Outside the grid the exact root solves are used (:func:`state`).

Regenerate (seconds)::

    python -m models.maugis_dugdale_static --rebuild
"""

from __future__ import annotations

import functools
import math
import pathlib
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from . import chebyshev
from . import maugis_dugdale_contact as md
from ._tables import rebuild_cli

__all__ = ["TABLE_PATH", "R_RANGE", "LAM_RANGE", "build", "load", "pull_off", "load_ratio",
           "state", "exact_state", "in_range", "static_overlap", "overlap_from_frequency",
           "frequency_from_overlap"]

TABLE_PATH = pathlib.Path(__file__).with_name("data") / "md_static.npz"
R_RANGE = (0.3, 1000.0)
"""The load ratios r = F0/Fc [-] tabulated (the Maugis-Dugdale backbone table's range)."""
LAM_RANGE = (0.1, 100.0)
"""The lam [-] tabulated (the law's prior range)."""
_P_EDGES = (math.log(R_RANGE[0]), math.log(10.0), math.log(R_RANGE[1]))
_Q_EDGES = (math.log(LAM_RANGE[0]), -1.0, 1.0, math.log(LAM_RANGE[1]))
_M = 24
_TABLE: dict[str, np.ndarray] = {}


def exact_state(r: ArrayLike, lam: ArrayLike) -> tuple[jnp.ndarray, ...]:
    """(ln n, ln D, Pbar_c) [-] by the root solves of :mod:`models.maugis_dugdale`."""
    lam = jnp.asarray(lam, float)
    pc = md.reduced_pull_off(lam)
    pbar = -jnp.asarray(r, float) * pc
    th = md.angle_from_load(pbar, lam)
    d0 = md.angle_state(th, lam)[2]
    return (jnp.log(d0 * md.reduced_slope(th, lam) / pbar),
            jnp.log(d0) - (2.0 / 3.0) * jnp.log(pbar), pc)


def _coefficients(values: np.ndarray, nu: np.ndarray) -> np.ndarray:
    # the tensor-product interpolant: along ln r, then along ln lam
    return chebyshev.to_chebyshev(chebyshev.to_chebyshev(values, nu, axis=0), nu, axis=1)


def build() -> dict[str, np.ndarray]:
    """The Chebyshev coefficients on every piece (deterministic)."""
    fn = jax.jit(jax.vmap(lambda p, q: exact_state(jnp.exp(p), jnp.exp(q))))
    nu = chebyshev.gauss_nodes(-1.0, 1.0, _M)[0]
    ln_n = np.empty((len(_P_EDGES) - 1, len(_Q_EDGES) - 1, _M, _M))
    ln_d = np.empty_like(ln_n)
    pc = np.empty((len(_Q_EDGES) - 1, _M))
    for i, (a, b) in enumerate(zip(_P_EDGES[:-1], _P_EDGES[1:])):
        for j, (c, d) in enumerate(zip(_Q_EDGES[:-1], _Q_EDGES[1:])):
            pp, qq = np.meshgrid(chebyshev.gauss_nodes(a, b, _M)[1],
                                 chebyshev.gauss_nodes(c, d, _M)[1], indexing="ij")
            vals = [np.asarray(v).reshape(pp.shape)
                    for v in fn(jnp.asarray(pp.ravel()), jnp.asarray(qq.ravel()))]
            ln_n[i, j] = _coefficients(vals[0], nu)
            ln_d[i, j] = _coefficients(vals[1], nu)
            pc[j] = chebyshev.to_chebyshev(vals[2][0], nu)
    return {"p_edges": np.asarray(_P_EDGES), "q_edges": np.asarray(_Q_EDGES),
            "ln_n": ln_n, "ln_d": ln_d, "pull_off": pc}


def load() -> dict[str, np.ndarray]:
    """The stored table (loaded once)."""
    if not _TABLE:
        with np.load(TABLE_PATH) as f:
            _TABLE.update({k: f[k] for k in f.files})
    return _TABLE


def _locate(z, edges):
    # (piece, local coordinate in [-1, 1]); clamped to the end pieces
    e = np.asarray(edges)
    k = sum((z >= b).astype(jnp.int32) for b in e[1:-1])
    lo, hi = jnp.asarray(e)[k], jnp.asarray(e)[k + 1]
    return k, jnp.clip((2.0 * z - (lo + hi)) / (hi - lo), -1.0, 1.0)


def _pull_off_table(lam):
    t = load()
    k, nu = _locate(jnp.log(lam), t["q_edges"])
    return jnp.sum(jnp.asarray(t["pull_off"])[k] * chebyshev.basis(nu, _M), axis=-1)


def in_range(r: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """True where (r, lam) lies on the tabulated grid (:data:`R_RANGE`, :data:`LAM_RANGE`)."""
    r, lam = jnp.asarray(r, float), jnp.asarray(lam, float)
    return ((r >= R_RANGE[0]) & (r <= R_RANGE[1]) & (lam >= LAM_RANGE[0] * (1 - 1e-12))
            & (lam <= LAM_RANGE[1] * (1 + 1e-12)))


def _choose(inside_fn, table_fn, exact_fn, *args):
    # one scalar point (the sampler's case): only the branch taken runs; arrays: both
    if all(jnp.ndim(a) == 0 for a in args):
        return _cond(inside_fn, table_fn, exact_fn, *(jnp.asarray(a, float) for a in args))
    inside = inside_fn(*args)
    return jax.tree_util.tree_map(lambda a, b: jnp.where(inside, a, b), table_fn(*args),
                                  exact_fn(*args))


@partial(jax.custom_jvp, nondiff_argnums=(0, 1, 2))
def _cond(inside_fn, table_fn, exact_fn, *args):
    return jax.lax.cond(inside_fn(*args), table_fn, exact_fn, *args)


@functools.cache
def _with_jacobian(fn):
    # one function object per branch: eager calls (the fold's probes) reuse the compiled
    # branches instead of tracing new closures at every call
    return lambda *a: (fn(*a), jax.jacfwd(fn, argnums=tuple(range(len(a))))(*a))


@_cond.defjvp
def _cond_jvp(inside_fn, table_fn, exact_fn, primals, tangents):
    # Why a rule of its own: differentiated through, lax.cond makes every gradient carry
    # the residuals of both branches (the root solves' too: 60 of a 65 us gradient of the
    # overlap map). Here the branch taken returns its values and its Jacobian in the
    # scalar arguments, and the tangent is formed outside the cond.
    out, jac = jax.lax.cond(inside_fn(*primals), _with_jacobian(table_fn),
                            _with_jacobian(exact_fn), *primals)
    # jac: out's structure, each leaf a tuple of its derivatives in the arguments
    tan = jax.tree_util.tree_map(
        lambda cols: sum(c * t for c, t in zip(cols, tangents)), jac,
        is_leaf=lambda v: isinstance(v, tuple) and not any(isinstance(e, tuple) for e in v))
    return out, tan


def _lam_inside(lam):
    return (lam >= LAM_RANGE[0] * (1 - 1e-12)) & (lam <= LAM_RANGE[1] * (1 + 1e-12))


def pull_off(lam: ArrayLike) -> jnp.ndarray:
    """Pbar_c(lam) = min Pbar [-] (models.maugis_dugdale.reduced_pull_off), tabulated on
    :data:`LAM_RANGE`, the root solve elsewhere."""
    lam = jnp.asarray(lam, float)
    return _choose(_lam_inside, _pull_off_table, md.reduced_pull_off, lam)


def load_ratio(load: ArrayLike, *, radius: ArrayLike, gamma: ArrayLike,
               lam: ArrayLike) -> jnp.ndarray:
    """r = F0/Fc [-], Fc = -Pbar_c(lam) pi w R the pull-off force [N] (w = 2 gamma)."""
    fs = md.scales(e_star=1.0, radius=radius, gamma=gamma)[2]
    return jnp.asarray(load, float) / (-pull_off(lam) * fs)


def _state_table(r, lam):
    t = load()
    i, nu_p = _locate(jnp.log(r), t["p_edges"])
    j, nu_q = _locate(jnp.log(lam), t["q_edges"])
    tp, tq = chebyshev.basis(nu_p, _M), chebyshev.basis(nu_q, _M)
    pick = lambda c: jnp.einsum("...a,...ab,...b->...", tp, jnp.asarray(c)[i, j], tq)
    return pick(t["ln_n"]), pick(t["ln_d"]), _pull_off_table(lam)


def state(r: ArrayLike, lam: ArrayLike) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """(ln n, ln D, Pbar_c) [-] at load ratio r and lam (module doc): the tables on their
    grid, the exact root solves elsewhere. Differentiable in both."""
    r, lam = jnp.asarray(r, float), jnp.asarray(lam, float)
    return _choose(in_range, _state_table, exact_state, r, lam)


def static_overlap(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
                   gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """delta0 = d_s D Pbar0^(2/3) [m] under the load F0 [N] (as
    :func:`models.maugis_dugdale.static_overlap`, from the tables)."""
    _, d_s, fs = md.scales(e_star=e_star, radius=radius, gamma=gamma)
    pbar0 = jnp.asarray(load, float) / fs
    _, ln_d, _ = state(load_ratio(load, radius=radius, gamma=gamma, lam=lam), lam)
    return d_s * jnp.exp(ln_d + (2.0 / 3.0) * jnp.log(pbar0))


def overlap_from_frequency(f0: ArrayLike, load: ArrayLike, mass: ArrayLike, *,
                           radius: ArrayLike, gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """delta0 = n F0/(m omega0^2) [m] at f0 [Hz] (as
    :func:`models.maugis_dugdale.overlap_from_frequency`, from the tables; E* drops out)."""
    ln_n, _, _ = state(load_ratio(load, radius=radius, gamma=gamma, lam=lam), lam)
    omega2 = jnp.square(2.0 * jnp.pi * jnp.asarray(f0, float))
    return jnp.exp(ln_n) * load / (mass * omega2)


def frequency_from_overlap(delta0: ArrayLike, load: ArrayLike, mass: ArrayLike, *,
                           radius: ArrayLike, gamma: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """f0 = (n F0/(m delta0))^(1/2)/(2 pi) [Hz]: the inverse of
    :func:`overlap_from_frequency`."""
    ln_n, _, _ = state(load_ratio(load, radius=radius, gamma=gamma, lam=lam), lam)
    return jnp.sqrt(jnp.exp(ln_n) * load / (mass * jnp.asarray(delta0, float))) / (2 * jnp.pi)


def _main(argv: list[str] | None = None) -> int:
    return rebuild_cli(argv, prog="python -m models.maugis_dugdale_static",
                       description="Tabulated Maugis-Dugdale static state.", build=build,
                       path=TABLE_PATH)


if __name__ == "__main__":
    raise SystemExit(_main())
