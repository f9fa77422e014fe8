"""The sweep curve of a law whose shape depends on one fitted parameter, folded into one
cubic per sweep point and cell of that parameter.

Why. For the table-driven laws every NUTS step evaluates a backbone table at every sweep
point. On the embedded data the whole curve (all 454 points) depends on a single
parameter: JKR and DMT on gamma (the overlap at the measured f0 and the load ratio both
follow from gamma alone), the power law on n, the rough sphere on its roughness factor;
Hertz's and the viscoelastic law's on none (XLA then folds the curve when it compiles).
Before sampling, the curve is therefore tabulated once along that parameter: in
z = ln theta, ``CELLS`` equal cells over the prior's central 1 - 2e-12, a cubic Hermite
piece per cell and point from the exact values and z-derivatives at the cell ends. A
step then reads one cell (4 numbers per point, four contiguous row slices) instead of
locating every point in a two-dimensional table, which on the CPU costs several times more.
(:mod:`inference.speed.steps` folds the per-protocol overlap map with the curve, where it
depends on the same parameter.)

Cost. Two details decide it on the CPU: the coefficients are kept as four
(cells, points) arrays, one row slice each (a slice of one (cells, points, 4) array read
with stride 4 costs several times more), and the derivative in z is a
rule of its own (``custom_jvp``) that returns the cubic's slope from inside the
``lax.cond``: differentiated through, the cond makes the forward pass carry the
residuals of both branches (the exact curve's intermediates, zeros when the fold is
taken) every step.

Honesty. The fold is checked where it is built: in every cell at z = 1/4, 1/2 and 3/4 of
its width against the exact curve. A cell whose error exceeds ``TOL`` (1e-7 in
Delta f/f0: an order below the most accurate table's stated error, 1e-6, and 1e-5 of the
embedded data's shift noise) is marked and never used; a sweep crossing the onset of
contact loss inside a cell (where the backbone is C1, not C2) can do that. There, and
outside the folded range, the model evaluates the exact curve (``lax.cond`` on the scalar
parameter: under ``vmap`` both branches run, still correct). The shape dependence is found
from the curve's program (the parameters whose values reach its outputs), and where two or
more do, numerically: the curve's forward derivative in each at two prior draws; a
parameter it does not depend on gets an exact zero. Any other case (no parameter, two or
more, data that are not concrete, a prior without a quantile function) is not folded.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax.extend.core import Literal

from beadrod.inference.speed.inner_branch import chosen
from beadrod.inference.speed.light_compile import one_shot
from beadrod.models.tables.hermite_cells import cubic, cubic_slope, hermite

__all__ = ["CELLS", "TOL", "TAIL", "REFINE", "Fold", "build_fold", "shape_parameter",
           "shape_parameters", "evaluate", "quantiles", "cached", "is_concrete"]

CELLS = 256
"""Cells along z = ln theta over the folded range."""
TOL = 1e-7
"""Largest fold error [-] in Delta f/f0 a cell may have and be used."""
TAIL = 1e-12
"""Prior mass left out at each end of the folded range."""
REFINE = 8
"""Sub-cells of a base cell whose one cubic missed TOL."""


@dataclass(frozen=True)
class Fold:
    """Per-point cubics of the sweep curve in z = ln theta on ``CELLS`` equal base cells
    from ``z_lo`` (width ``width``), base cell j cut into ``count[j]`` equal sub-cells
    (``REFINE`` where one cubic missed ``TOL``), stored flat from ``offset[j]``:
    ``coef`` (sub-cells, points, 4), powers of (z - z_k) highest first; ``usable``
    (sub-cells,) bool; ``max_error`` [-] the largest checked error of the usable ones."""

    param: str
    z_lo: float
    width: float
    count: np.ndarray
    offset: np.ndarray
    coef: np.ndarray
    usable: np.ndarray
    max_error: float

    @property
    def cells(self) -> int:
        return int(self.count.size)


def shape_parameter(curve: Callable[[dict], jnp.ndarray], draws: list[dict]) -> str | None:
    """The one parameter ``curve(theta)`` depends on at every draw, else None
    (:func:`shape_parameters`)."""
    names = shape_parameters(curve, draws)
    return names[0] if len(names) == 1 else None


def shape_parameters(curve: Callable[[dict], jnp.ndarray], draws: list[dict]) -> tuple[str, ...]:
    """The parameters ``curve(theta)`` depends on at some draw, in the draws' key order.

    First by data flow: a parameter that reaches no output of the curve's program has an
    exactly zero derivative, and one that reaches it alone is the curve's parameter (a
    curve that reaches it only through terms of zero derivative is then folded needlessly,
    still exactly). Where two or more reach it, numerically: the curve's forward
    derivative in each of them at every draw."""
    names = list(draws[0])
    args = [{k: jnp.asarray(theta[k], float) for k in names} for theta in draws]
    reached = _reached(curve, args[0])
    if reached is not None and len(reached) <= 1:
        return tuple(k for k in names if k in reached)
    probed = names if reached is None else [k for k in names if k in reached]
    # one program for every draw and probed parameter (a unit tangent each, vmapped;
    # inference.speed.light_compile): run op by op, the curve's forward derivatives would be most
    # of the fold's build
    unit = {k: jnp.stack([jnp.full(jnp.shape(args[0][k]), float(k == j)) for j in probed])
            for k in names}
    derivative = jax.vmap(lambda theta, t: jax.jvp(curve, (theta,), (t,))[1],
                          in_axes=(None, 0))
    run = one_shot(derivative, args[0], unit)
    used: set[str] = set()
    for theta in args:
        dc = np.asarray(run(theta, unit))
        used.update(k for j, k in enumerate(probed) if np.any(dc[j] != 0.0))
    return tuple(k for k in names if k in used)


def _reached(curve: Callable[[dict], jnp.ndarray], theta: dict) -> set[str] | None:
    # the parameters whose values flow into the outputs of curve's jaxpr (an equation's
    # outputs depend on all its inputs: nested programs are taken whole, which can only
    # add parameters); None where the curve cannot be traced so (then every parameter is
    # probed). Tracing is far cheaper than compiling the numerical probe
    names = list(theta)
    try:
        closed = jax.make_jaxpr(lambda *v: curve(dict(zip(names, v))))(
            *[theta[k] for k in names])
    except Exception:   # noqa: BLE001 - any tracing failure: probe numerically instead
        return None
    jaxpr = closed.jaxpr
    deps: dict[Any, set[str]] = {v: {k} for v, k in zip(jaxpr.invars, names)}

    def of(atoms) -> set[str]:
        out: set[str] = set()
        for v in atoms:
            if not isinstance(v, Literal):
                out |= deps.get(v, set())
        return out

    for eqn in jaxpr.eqns:
        reached = of(eqn.invars)
        for v in eqn.outvars:
            deps[v] = reached
    return of(jaxpr.outvars)


_BATCH = 512   # parameter values per probe call: one compiled shape for every call
_CHECKS = (0.25, 0.5, 0.75)


def build_fold(curve: Callable[[dict], jnp.ndarray], theta: dict, param: str,
               lo: float, hi: float,
               counted: Callable[[dict], jnp.ndarray] | None = None) -> Fold | None:
    """The fold of ``curve`` in ``param`` on [lo, hi] (> 0), the other parameters held at
    ``theta``'s values (the curve does not depend on them), or None if the curve is not
    finite there. ``counted(theta)``: False where the model gives zero likelihood whatever
    the curve (a point outside the law's domain); the fold is checked only where it is
    True, and a cell with no counted check point is usable (its value never counts)."""
    if not (0.0 < lo < hi and np.isfinite(hi)):
        return None
    z_lo, z_hi = float(np.log(lo)), float(np.log(hi))
    h = (z_hi - z_lo) / CELLS
    others = {k: jnp.asarray(v) for k, v in theta.items() if k != param}

    def one(z):
        th = {**others, param: jnp.exp(z)}
        f, d = jax.jvp(lambda zz: curve({**others, param: jnp.exp(zz)}), (z,),
                       (jnp.ones_like(z),))
        return f, d, (jnp.asarray(True) if counted is None else counted(th))

    batch = jax.jit(jax.vmap(one))

    def probe(z: np.ndarray):
        out = [[], [], []]
        for k in range(0, z.size, _BATCH):
            part = z[k:k + _BATCH]
            res = batch(jnp.asarray(np.pad(part, (0, _BATCH - part.size), mode="edge")))
            for acc, a in zip(out, res):
                acc.append(np.asarray(a)[:part.size])
        return tuple(np.concatenate(a) for a in out)

    def cells(starts: np.ndarray, w: float):
        # Hermite cubics on [s, s + w] for every start s, and their checked errors
        nodes = np.concatenate([starts, starts + w])
        checks = np.concatenate([starts + c * w for c in _CHECKS])
        f, d, _ = probe(nodes)
        fc, _, ok = probe(checks)
        n = starts.size
        coef = hermite(f[:n], f[n:], d[:n], d[n:], w)          # (cells, points, 4)
        err = np.zeros(n)
        for m, c in enumerate(_CHECKS):
            miss = np.max(np.abs(cubic(coef, c * w) - fc[m * n:(m + 1) * n]), axis=1)
            err = np.maximum(err, np.where(ok[m * n:(m + 1) * n], miss, 0.0))
        finite = np.all(np.isfinite(coef), axis=(1, 2))
        return coef, np.where(finite, err, np.inf)

    coef, err = cells(z_lo + h * np.arange(CELLS), h)
    count = np.where(err <= TOL, 1, REFINE)
    parts_c, parts_e = [], []
    fine = iter(())
    bad = np.nonzero(count > 1)[0]
    if bad.size:
        starts = (z_lo + h * bad[:, None] + (h / REFINE) * np.arange(REFINE)).ravel()
        fc, fe = cells(starts, h / REFINE)
        fine = iter(zip(fc.reshape(bad.size, REFINE, *fc.shape[1:]),
                        fe.reshape(bad.size, REFINE)))
    for j in range(CELLS):
        if count[j] == 1:
            parts_c.append(coef[j:j + 1])
            parts_e.append(err[j:j + 1])
        else:
            c, e = next(fine)
            parts_c.append(c)
            parts_e.append(e)
    coef, err = np.concatenate(parts_c), np.concatenate(parts_e)
    usable = err <= TOL
    if not np.any(usable):
        return None
    return Fold(param, z_lo, h, count, np.cumsum(count) - count, np.ascontiguousarray(coef),
                usable, float(np.max(err[usable])))


def evaluate(fold: Fold, theta: dict, exact: Callable[[dict], jnp.ndarray]) -> jnp.ndarray:
    """The curve at ``theta``: the fold's cell where it is usable, else ``exact(theta)``.

    Differentiable in ``fold.param`` only: the other parameters are passed through to
    ``exact`` but get no derivative, as the fold presumes (:func:`shape_parameter`)."""
    z = jnp.log(jnp.asarray(theta[fold.param], float))
    others = {k: v for k, v in theta.items() if k != fold.param}
    return chosen(partial(_value, fold, exact), z, others)


def _locate(fold: Fold, z):
    # (flat sub-cell index, offset of z in it, usable?)
    pos = (z - fold.z_lo) / fold.width
    j = jnp.clip(jnp.floor(jnp.nan_to_num(pos)).astype(jnp.int32), 0, fold.cells - 1)
    n = jnp.asarray(fold.count)[j]
    w = fold.width / n.astype(float)
    start = fold.z_lo + fold.width * j.astype(float)
    k = jnp.clip(jnp.floor(jnp.nan_to_num((z - start) / w)).astype(jnp.int32), 0, n - 1)
    flat = jnp.asarray(fold.offset)[j] + k
    use = (pos >= 0.0) & (pos < fold.cells) & jnp.asarray(fold.usable)[flat]
    return flat, z - (start + w * k.astype(float)), use


def _rows(fold: Fold, flat):
    # the sub-cell's four coefficient rows, one slice of each (cells, points) array: on
    # the CPU one slice of the (cells, points, 4) array, then strided reads, cost more
    return [jax.lax.dynamic_index_in_dim(jnp.asarray(fold.coef[..., m]), flat, 0,
                                         keepdims=False) for m in range(4)]


def _value(fold, exact, z, others, slope: bool):
    flat, t, use = _locate(fold, z)

    def folded(z, others):
        c = jnp.stack(_rows(fold, flat), axis=-1)
        return (cubic(c, t), cubic_slope(c, t)) if slope else cubic(c, t)

    def direct(z, others):
        f = lambda zz: exact({**others, fold.param: jnp.exp(zz)})  # noqa: E731
        return jax.jvp(f, (z,), (jnp.ones_like(z),)) if slope else f(z)

    # under vmap lax.cond runs both branches (still correct); NUTS takes one
    return jax.lax.cond(use, folded, direct, z, others)


_CACHE: OrderedDict[str, Fold | None] = OrderedDict()
_CACHE_SIZE = 8   # folds kept (a few MB each): the laws of one comparison, not every
                  # simulated dataset of a calibration run


def cached(key_parts: tuple, make: Callable[[], Fold | None]) -> Fold | None:
    """``make()`` once per key (the law, its rung and priors, the data's bytes): a model is
    traced several times per fit (mode search, warmup, draws, evidence)."""
    h = hashlib.sha256()
    for part in key_parts:
        h.update(np.asarray(part).tobytes() if isinstance(part, np.ndarray)
                 else repr(part).encode())
    key = h.hexdigest()
    if key in _CACHE:
        _CACHE.move_to_end(key)
    else:
        _CACHE[key] = make()
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    return _CACHE[key]


def quantiles(d: Any, qs: tuple[float, ...]) -> list | None:
    """The quantiles ``qs`` of the numpyro distribution ``d``, or None when its class has
    no quantile function (then the fold has no range to cover and is not built)."""
    import numpyro.distributions as dist

    if type(d).icdf is dist.Distribution.icdf:
        return None
    return [d.icdf(jnp.asarray(q)) for q in qs]


def is_concrete(*arrays: Any) -> bool:
    """True when none of ``arrays`` is a tracer (the fold is built from concrete data)."""
    return not any(isinstance(a, jax.core.Tracer) for a in arrays)
