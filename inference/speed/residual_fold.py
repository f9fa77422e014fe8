"""The drive sweeps' Normal likelihood of a law whose curve depends on two fitted
parameters, folded into two functions of those parameters.

Why. :mod:`inference.speed.fold` folds a curve that depends on one parameter: a cubic per sweep
point and cell. A curve that depends on two (Maugis-Dugdale's, on gamma and lambda: the
load ratio and the transition parameter set its shape, and the overlap at the measured
f0 follows from them) would need a bicubic per point and cell: tens of MB at a useful
resolution, and a step still reads every point. The Normal likelihood of the sweeps needs
less. With shift_i ~ Normal(f_i + o d_i, sigma) (f the curve, o the down-sweep offset,
d_i the direction),

    sum_i (y_i - o d_i - f_i)^2 = S0 - 2 o S1 + o^2 D,
    S0 = sum_i (y_i - f_i)^2,   S1 = sum_i d_i (y_i - f_i),   D = sum_i d_i^2,

so the whole log-likelihood, -(S0 - 2 o S1 + o^2 D)/(2 sigma^2) - N ln sigma
- (N/2) ln 2 pi, reads the curve through two numbers. S0 and S1 are folded: bicubic
Hermite pieces in (z_a, z_b) = (ln theta_a, ln theta_b) on ``CELLS`` x ``CELLS`` equal
cells over the region the data leave plausible (``COARSE``, ``REGION``: a coarse grid of
the profile log-likelihood with the log prior, inside the priors' central 1 - 2e-12
widened by half on each side, as a posterior pushed by strong data can lie beyond it),
from the nodes' exact values and their first and mixed derivatives by fourth-order
differences. A step reads one cell: 32 numbers, whatever the number of sweeps.

Accuracy, in the unit that matters: the log-likelihood. An error (dS0, dS1) shifts it by
(dS0 - 2 o dS1)/(2 sigma^2). Where a sweep crosses the onset of contact loss inside a
cell its curve has a corner (C1, not C2), but in S0 - 2 o S1 the corner enters weighted by
that sweep's residual y_i - o d_i - f_i, of the order of the noise, not of the shift.
Every cell is checked where it is built, at three points against the exact sums: its
error bound is (|dS0 - 2 o_hat dS1| + 2 dO |dS1|)/(2 sigma_ref^2), with o_hat and
sigma_hat the offset and noise of the best node (profile maximum of the likelihood over
the nodes), dO = 10 sigma_hat/sqrt(D) (ten posterior sd of the offset) and sigma_ref =
sigma_hat/2. A cell whose bound exceeds ``TOL`` (1e-3 nats) is marked and never used,
and so is one with a corner or check point outside the law's domain; there, and outside
the folded range, the model evaluates the exact sums (``lax.cond``; under ``vmap`` both
branches run, still correct). Data fitted with less noise than sigma_ref would see larger
errors (as (sigma_ref/sigma)^2): the posterior of sigma does not go there (its relative sd
is 1/sqrt(2 N), 3 % on the embedded data).

Where it is used: the point-wise log-likelihood (LOO), the posterior and prior predictive
and a Student-t likelihood need the curve itself; the model then evaluates it exactly
(``data[POINTWISE]`` asks for that; :mod:`inference.sampling.draws` sets it).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.inference.speed.inner_branch import chosen

__all__ = ["CELLS", "COARSE", "REGION", "TOL", "POINTWISE", "ResidualFold",
           "build_residual_fold", "sums", "log_likelihood"]

CELLS = 192
"""Cells along each of the two folded coordinates z = ln theta, over the plausible region."""
COARSE = 64
"""Cells along each coordinate of the coarse grid that finds the plausible region."""
REGION = 25.0
"""The plausible region [nats]: where the profile log-likelihood with the log prior lies
within this of its largest value on the coarse grid."""
TOL = 1e-3
"""Largest error bound [nats] of the log-likelihood a cell may have and be used."""
POINTWISE = "pointwise"
"""The model-input key that asks a model for its point-wise likelihood (the exact curve)."""

_BATCH = 4096                                  # points per build call: one compiled shape
_CHECKS = ((0.5, 0.5), (0.25, 0.75), (0.75, 0.25))


@dataclass(frozen=True)
class ResidualFold:
    """Bicubic Hermite pieces of (S0, S1) in z = (ln theta_a, ln theta_b) on equal cells
    from ``z_lo`` (widths ``width``): ``nodes`` (cells_a + 1, cells_b + 1, 2, 4), for each
    sum its value and derivatives d/dz_a, d/dz_b, d2/dz_a dz_b, each times the widths of
    the coordinates it is taken in; ``usable`` (cells_a, cells_b); ``max_error`` [nats]
    the largest error bound of the usable cells at ``sigma_ref``."""

    params: tuple[str, str]
    z_lo: tuple[float, float]
    width: tuple[float, float]
    nodes: np.ndarray
    usable: np.ndarray
    max_error: float
    sigma_ref: float
    offset_ref: float
    offset_span: float

    @property
    def cells(self) -> tuple[int, int]:
        return tuple(int(n) for n in self.usable.shape)  # type: ignore[return-value]


def _basis(t):
    # cubic Hermite basis on [0, 1] (values at 0 and 1, then slopes at 0 and 1) and its
    # derivative, as (2 kinds, 2 ends)
    t2, t3 = t * t, t * t * t
    b = jnp.array([[1.0 - 3.0 * t2 + 2.0 * t3, 3.0 * t2 - 2.0 * t3],
                   [t - 2.0 * t2 + t3, t3 - t2]])
    d = jnp.array([[6.0 * (t2 - t), 6.0 * (t - t2)],
                   [1.0 - 4.0 * t + 3.0 * t2, 3.0 * t2 - 2.0 * t]])
    return b, d


def _patch(corners, u, v):
    # corners (2, 2, sums, 4): a, b, sum, [value, D_a, D_b, D_ab] with the derivative
    # kinds ordered k = kind_a + 2 kind_b; value and (d/du, d/dv) of every sum
    c = corners.reshape(2, 2, -1, 2, 2)                           # a, b, s, kind_b, kind_a
    bu, du = _basis(u)
    bv, dv = _basis(v)
    f = lambda x, y: jnp.einsum("ta,absvt,vb->s", x, c, y)  # noqa: E731
    return f(bu, bv), f(du, bv), f(bu, dv)


def build_residual_fold(exact: Callable[[dict], jnp.ndarray], theta: dict,
                        params: tuple[str, str], ranges: tuple[tuple[float, float], ...],
                        counted: Callable[[dict], jnp.ndarray],
                        log_prior: Callable[[dict], jnp.ndarray], n_points: int,
                        d2: float) -> ResidualFold | None:
    """The fold of ``exact(theta)`` = (S0, S1) in ``params``, the other parameters held at
    ``theta``'s values (the curve does not depend on them), over the region the data leave
    plausible (module doc) within ``ranges`` (each (lo, hi) > 0, the priors' central
    range) widened by half their width on each side; ``counted(theta)`` False where the
    model gives zero likelihood whatever the curve; ``log_prior(theta)`` the two
    parameters' log prior density; ``n_points`` the sweeps N, ``d2`` = D. None where no
    cell is usable."""
    lo = np.log([r[0] for r in ranges])
    hi = np.log([r[1] for r in ranges])
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi > lo)):
        return None
    lo, hi = lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo)
    others = {k: jnp.asarray(v) for k, v in theta.items() if k not in params}
    at = lambda z: {**others, params[0]: jnp.exp(z[0]), params[1]: jnp.exp(z[1])}  # noqa: E731

    def value(z):
        th = at(z)
        # the log prior density of z = ln theta: of theta, times theta
        return exact(th), counted(th), log_prior(th) + z[0] + z[1]

    # where the data leave the two parameters plausible: the profile log-likelihood of a
    # coarse grid (offset and noise at their best, (S0 - S1^2/D) = N sigma^2) with the
    # log prior, within REGION nats of its largest value, one coarse cell added around
    ga, gb = (np.linspace(lo[k], hi[k], COARSE + 1) for k in range(2))
    zz = np.stack(np.meshgrid(ga, gb, indexing="ij"), -1).reshape(-1, 2)
    values = _program(value)
    s, ok, lp = _run(values, zz)
    prof = s[:, 0] - s[:, 1] ** 2 / d2
    ok = ok & np.all(np.isfinite(s), axis=1) & np.isfinite(lp) & (prof > 0.0)
    if not np.any(ok):
        return None
    ell = np.where(ok, -0.5 * n_points * np.log(np.where(ok, prof, 1.0)) + lp, -np.inf)
    near = (ell >= np.max(ell) - REGION).reshape(COARSE + 1, COARSE + 1)
    box = []
    for axis, g in zip((1, 0), (ga, gb)):
        idx = np.nonzero(np.any(near, axis=axis))[0]
        box.append((g[max(idx[0] - 1, 0)], g[min(idx[-1] + 1, COARSE)]))
    lo, hi = np.array([b[0] for b in box]), np.array([b[1] for b in box])
    w = (hi - lo) / CELLS
    # the nodes' values, with two more on each side for the derivatives: fourth-order
    # central differences (d/dz_a, d/dz_b, then d/dz_a of d/dz_b); the nodes' exact
    # derivatives (nested forward derivatives of the curve) compile and run several
    # times slower than the values
    pad = np.arange(-2, CELLS + 3)
    ga, gb = lo[0] + w[0] * pad, lo[1] + w[1] * pad
    zz = np.stack(np.meshgrid(ga, gb, indexing="ij"), -1).reshape(-1, 2)
    s, ok, _ = _run(values, zz)
    m = CELLS + 5
    s, ok = s.reshape(m, m, 2), ok.reshape(m, m) & np.all(np.isfinite(s.reshape(m, m, 2)), -1)
    s = np.where(ok[..., None], s, 0.0)
    sa, ok_a = _difference(s, ok, 0)
    sb, ok_b = _difference(s, ok, 1)
    sab, ok_ab = _difference(sb, ok_b, 0)
    inner = (slice(2, -2), slice(2, -2))
    # (CELLS + 1, CELLS + 1, 2, 4): the differences are derivatives times the widths
    data = np.stack([s[inner], sa[:, 2:-2], sb[2:-2], sab], -1)
    ok = ok[inner] & ok_a[:, 2:-2] & ok_b[2:-2] & ok_ab
    ga, gb = ga[2:-2], gb[2:-2]
    # the best node: profile maximum over the offset (o = S1/D) and sigma (sigma^2 = P/N)
    prof = np.where(ok, data[..., 0, 0] - data[..., 1, 0] ** 2 / d2, np.inf)
    best = np.unravel_index(np.argmin(prof), prof.shape)
    sigma_hat = float(np.sqrt(prof[best] / n_points))
    o_hat = float(data[best][1, 0] / d2)
    if not (np.isfinite(sigma_hat) and sigma_hat > 0.0):
        return None
    sigma_ref, d_o = 0.5 * sigma_hat, 10.0 * sigma_hat / np.sqrt(d2)
    nodes = np.where(np.isfinite(data), data, 0.0)
    cell_ok = ok[:-1, :-1] & ok[1:, :-1] & ok[:-1, 1:] & ok[1:, 1:]
    corner = np.stack(np.meshgrid(ga[:-1], gb[:-1], indexing="ij"), -1)
    err = np.zeros((CELLS, CELLS))
    for c in _CHECKS:
        exact_s, inside, _ = _run(values, (corner + np.asarray(c) * w).reshape(-1, 2))
        ds = _interpolate_all(nodes, c) - exact_s.reshape(CELLS, CELLS, 2)
        bound = (np.abs(ds[..., 0] - 2.0 * o_hat * ds[..., 1]) + 2.0 * d_o * np.abs(ds[..., 1]))
        bound = bound / (2.0 * sigma_ref ** 2)
        cell_ok &= inside.reshape(CELLS, CELLS)
        err = np.maximum(err, np.where(np.isfinite(bound), bound, np.inf))
    usable = cell_ok & (err <= TOL)
    if not np.any(usable):
        return None
    return ResidualFold(tuple(params), (float(lo[0]), float(lo[1])), (float(w[0]), float(w[1])),
                        np.ascontiguousarray(nodes), usable, float(np.max(err[usable])),
                        sigma_ref, o_hat, float(d_o))


def _difference(f: np.ndarray, ok: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    # the fourth-order central difference of f along axis, in units of the node spacing
    # (two nodes fewer on each side), and where all five nodes are valid
    n = f.shape[axis]
    t = lambda a, k: np.take(a, np.arange(2 + k, n - 2 + k), axis=axis)  # noqa: E731
    d = (t(f, -2) - 8.0 * t(f, -1) + 8.0 * t(f, 1) - t(f, 2)) / 12.0
    valid = t(ok, -2) & t(ok, -1) & t(ok, 0) & t(ok, 1) & t(ok, 2)
    return d, valid


def _run(prog: Callable, z: np.ndarray) -> list[np.ndarray]:
    # prog (a :func:`_program`) at every row of z (points, 2), in batches of one shape
    out: list[list[np.ndarray]] = []
    for k in range(0, len(z), _BATCH):
        part = z[k:k + _BATCH]
        res = prog(jnp.asarray(np.pad(part, ((0, _BATCH - len(part)), (0, 0)), mode="edge")))
        out = out or [[] for _ in res]
        for acc, a in zip(out, res):
            acc.append(np.asarray(a)[:len(part)])
    return [np.concatenate(a) for a in out]


def _program(fn: Callable) -> Callable:
    # fn over a batch of points, one after another: vmapped, a tabulated law reads a
    # table patch per point, slower than in sequence
    return jax.jit(lambda zz: jax.lax.map(fn, zz))


def _interpolate_all(nodes: np.ndarray, c) -> np.ndarray:
    # the folded sums at offset c (in cell units) of every cell: (cells_a, cells_b, 2)
    u, v = c
    corners = np.stack([np.stack([nodes[:-1, :-1], nodes[:-1, 1:]], 2),
                        np.stack([nodes[1:, :-1], nodes[1:, 1:]], 2)], 2)   # i, j, a, b, s, k
    fn = jax.vmap(jax.vmap(lambda cc: _patch(cc, u, v)[0]))
    return np.asarray(fn(jnp.asarray(corners)))


def sums(fold: ResidualFold, theta: dict, exact: Callable[[dict], jnp.ndarray]) -> jnp.ndarray:
    """(S0, S1) at ``theta``: the fold's cell where it is usable, else ``exact(theta)``.
    Differentiable in the two folded parameters only (the others get no derivative: the
    curve does not depend on them)."""
    z = jnp.log(jnp.stack([jnp.asarray(theta[k], float) for k in fold.params]))
    others = {k: v for k, v in theta.items() if k not in fold.params}
    return chosen(partial(_value, fold, exact), z, others)


def _value(fold, exact, z, others, slope: bool):
    lo, w = jnp.asarray(fold.z_lo), jnp.asarray(fold.width)
    pos = (z - lo) / w
    cells = jnp.asarray(fold.cells)
    ij = jnp.clip(jnp.floor(jnp.nan_to_num(pos)).astype(jnp.int32), 0, cells - 1)
    t = pos - ij.astype(float)
    use = jnp.all((pos >= 0.0) & (pos < cells)) & jnp.asarray(fold.usable)[ij[0], ij[1]]

    def folded(z, others):
        c = jax.lax.dynamic_slice(jnp.asarray(fold.nodes), (ij[0], ij[1], 0, 0), (2, 2, 2, 4))
        f, fu, fv = _patch(c, t[0], t[1])
        return (f, jnp.stack([fu / w[0], fv / w[1]], -1)) if slope else f

    def direct(z, others):
        g = lambda zz: exact({**others, fold.params[0]: jnp.exp(zz[0]),  # noqa: E731
                              fold.params[1]: jnp.exp(zz[1])})
        if not slope:
            return g(z)
        # two forward derivatives one after the other: vmapped over the tangents
        # (jax.jacfwd), a tabulated law reads a table patch per tangent (several times
        # slower: this branch is what a step outside the fold costs)
        v, ja = jax.jvp(g, (z,), (jnp.array([1.0, 0.0]),))
        jb = jax.jvp(g, (z,), (jnp.array([0.0, 1.0]),))[1]
        return v, jnp.stack([ja, jb], -1)

    # under vmap lax.cond runs both branches (still correct); NUTS takes one
    return jax.lax.cond(use, folded, direct, z, others)


def log_likelihood(s: jnp.ndarray, offset, sigma, n_points: int, d2: float) -> jnp.ndarray:
    """sum_i ln Normal(y_i | f_i + o d_i, sigma) [nats] from (S0, S1) (module doc)."""
    r = s[0] - 2.0 * offset * s[1] + offset * offset * d2
    return -0.5 * r / (sigma * sigma) - n_points * jnp.log(sigma) \
        - 0.5 * n_points * np.log(2.0 * np.pi)
