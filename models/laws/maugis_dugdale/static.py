"""The Maugis-Dugdale static state under the load, tabulated: the law's overlap maps.

Why. At a load F0 > 0 the reduced state of a Maugis-Dugdale contact (module
:mod:`models.laws.maugis_dugdale`) follows from two numbers, the load ratio r = F0/Fc (Fc =
-Pbar_c(lam) pi w R, the load-controlled pull-off force) and Maugis' lam: theta0 =
theta(Pbar0, lam) with Pbar0 = F0/(pi w R) = -r Pbar_c(lam). The exact maps need two
bracketed root solves (pull-off angle, then the load's angle; 120 Newton steps), slow in
a sampler's step and slow to compile with their derivatives, and a sampler's log density
calls the maps at ten sites. Tabulated
here, as Chebyshev interpolants, on the whole load range r in (0, inf) for every lam of
the law's parameter range :data:`LAM_RANGE` (its prior's support):

    Pbar_c(lam)                                  [-]  (pull-off, -2 .. -3/2),
    ln n(r, lam),     n = Delta0 k0 / Pbar0      [-]  (delta0 = n F0/(m omega0^2)),
    ln D(r, lam),     D = Delta0 / Pbar0^(2/3)   [-]  (delta0 = d_s Delta0),

k0 = dPbar/dDelta at the state. n is the law's "effective exponent" (3/2 for Hertz, which
n and D = 1 reach as r -> inf); the f0 -> overlap map of :mod:`models.laws.maugis_dugdale`
(the elastic scale scatters, not the adhesion) is delta0 = n F0/(m omega0^2) exactly.

Pieces in r, each in the coordinate in which the state is smooth up to its end:

* r in (0, 0.3], in r itself: n r and D r^(2/3) (tabulated as ln n + ln r and
  ln D + (2/3) ln r) tend to the zero-load state's values, a regular point (the nearest
  singularity is pull-off, r = -1);
* r in [0.3, 10] and [10, 1000], in ln r;
* r in [1000, inf), in w = r^(-1/2) in [0, 1000^(-1/2)]: the state tends to Hertz's as
  ln n - ln(3/2) ~ 0.6 w^2 (w^3 next; measured from the root solves up to r = 1e12).

lam in [0.1, 100] in three pieces of ln lam split at -1 and 1 (the DMT-JKR transition),
24 x 24 Chebyshev terms per piece; Pbar_c in the same three pieces. Measured against the
root solves at random points in every piece (tests/test_maugis_dugdale_static.py): within
1e-13. Outside :data:`LAM_RANGE`, or at a load r <= 0, the maps return NaN: lam is a
parameter of the law only on its prior's support (``beadrod shift`` refuses other values);
:func:`exact_state` (the root solves) takes any lam.

Regenerate (seconds)::

    python -m beadrod.models.laws.maugis_dugdale.static --rebuild
"""

from __future__ import annotations

import math
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.laws.maugis_dugdale import contact
from beadrod.models.tables import chebyshev
from beadrod.models.tables.rebuild import rebuild_cli

__all__ = ["TABLE_PATH", "R_EDGES", "LAM_RANGE", "build", "load", "pull_off", "load_ratio",
           "state", "contact_state", "exact_state", "in_range", "static_overlap",
           "overlap_from_frequency", "frequency_from_overlap"]

TABLE_PATH = pathlib.Path(__file__).with_name("data") / "md_static.npz"
R_EDGES = (0.3, 10.0, 1000.0)
"""The load ratios r = F0/Fc [-] where the pieces in r meet (module doc)."""
LAM_RANGE = (0.1, 100.0)
"""The lam [-] tabulated (the law's prior range)."""
_Q_EDGES = (math.log(LAM_RANGE[0]), -1.0, 1.0, math.log(LAM_RANGE[1]))
_W_MAX = R_EDGES[-1] ** -0.5
_M = 24
_TINY = 1e-300
_TABLE: dict[str, np.ndarray] = {}


def exact_state(r: ArrayLike, lam: ArrayLike) -> tuple[jnp.ndarray, ...]:
    """(ln n, ln D, Pbar_c) [-] by the root solves of :mod:`models.laws.maugis_dugdale`."""
    lam = jnp.asarray(lam, float)
    pc = contact.reduced_pull_off(lam)
    pbar = -jnp.asarray(r, float) * pc
    th = contact.angle_from_load(pbar, lam)
    d0 = contact.angle_state(th, lam)[2]
    return (jnp.log(d0 * contact.reduced_slope(th, lam) / pbar),
            jnp.log(d0) - (2.0 / 3.0) * jnp.log(pbar), pc)


def _piece_nodes(k: int, nu: np.ndarray) -> np.ndarray:
    # the load ratios r at local coordinates nu of r-piece k (inverse of _r_coordinate)
    lo, hi = _piece_span(k)
    c = 0.5 * (lo + hi) + 0.5 * (hi - lo) * nu
    if k == 0:
        return c
    return c ** -2.0 if k == len(R_EDGES) else np.exp(c)


def _piece_span(k: int) -> tuple[float, float]:
    # piece k's range in its own coordinate: r, ln r, ln r, w = r^(-1/2)
    if k == 0:
        return 0.0, R_EDGES[0]
    if k == 3:
        return 0.0, _W_MAX
    return math.log(R_EDGES[k - 1]), math.log(R_EDGES[k])


def _offset(k: int, r: np.ndarray) -> np.ndarray:
    # what is added to ln n in piece k (ln r on the first, where n ~ 1/r; else 0)
    return np.log(r) if k == 0 else np.zeros_like(r)


def _coefficients(values: np.ndarray, nu: np.ndarray) -> np.ndarray:
    # the tensor-product interpolant: along r's coordinate, then along ln lam
    return chebyshev.to_chebyshev(chebyshev.to_chebyshev(values, nu, axis=0), nu, axis=1)


def build() -> dict[str, np.ndarray]:
    """The Chebyshev coefficients on every piece (deterministic)."""
    fn = jax.jit(jax.vmap(lambda r, q: exact_state(r, jnp.exp(q))))
    nu = chebyshev.gauss_nodes(-1.0, 1.0, _M)[0]
    ln_n = np.empty((len(R_EDGES) + 1, len(_Q_EDGES) - 1, _M, _M))
    ln_d = np.empty_like(ln_n)
    pc = np.empty((len(_Q_EDGES) - 1, _M))
    for i in range(len(R_EDGES) + 1):
        for j, (c, d) in enumerate(zip(_Q_EDGES[:-1], _Q_EDGES[1:])):
            rr, qq = np.meshgrid(_piece_nodes(i, nu), chebyshev.gauss_nodes(c, d, _M)[1],
                                 indexing="ij")
            vals = [np.asarray(v).reshape(rr.shape)
                    for v in fn(jnp.asarray(rr.ravel()), jnp.asarray(qq.ravel()))]
            off = _offset(i, rr)
            ln_n[i, j] = _coefficients(vals[0] + off, nu)
            ln_d[i, j] = _coefficients(vals[1] + (2.0 / 3.0) * off, nu)
            pc[j] = chebyshev.to_chebyshev(vals[2][0], nu)
    return {"r_edges": np.asarray(R_EDGES), "q_edges": np.asarray(_Q_EDGES),
            "ln_n": ln_n, "ln_d": ln_d, "pull_off": pc}


def load() -> dict[str, np.ndarray]:
    """The stored table (loaded once)."""
    if not _TABLE:
        with np.load(TABLE_PATH) as f:
            _TABLE.update({k: f[k] for k in f.files})
    return _TABLE


def _lam_coordinate(lam):
    # (piece, local coordinate in [-1, 1]) of ln lam. Outside the range lam is replaced by
    # an inside value (callers mask the result), not clamped: a clamp would halve the
    # derivative at the range's ends
    z = jnp.log(jnp.where(_valid(lam), lam, 1.0))
    k = sum((z >= b).astype(jnp.int32) for b in _Q_EDGES[1:-1])
    e = jnp.asarray(_Q_EDGES)
    lo, hi = e[k], e[k + 1]
    return k, (2.0 * z - (lo + hi)) / (hi - lo)


def _r_coordinate(r):
    # (piece, local coordinate in [-1, 1], ln-n offset) of the load ratio r > 0. Each piece's
    # coordinate is formed from r masked into its own range (double where), so that the
    # unused ones (ln r at r -> 0, r^(-1/2)) give no infinite derivative to the others
    k = sum((r >= b).astype(jnp.int32) for b in R_EDGES)
    r_mid = jnp.where((k == 1) | (k == 2), r, 1.0)
    r_far = jnp.where(k == 3, r, R_EDGES[-1])
    r_low = jnp.where(k == 0, jnp.maximum(r, _TINY), 1.0)
    spans = [_piece_span(i) for i in range(len(R_EDGES) + 1)]
    coords = [r, jnp.log(r_mid), jnp.log(r_mid), r_far ** -0.5]
    nu = sum(jnp.where(k == i, (2.0 * c - (lo + hi)) / (hi - lo), 0.0)
             for i, (c, (lo, hi)) in enumerate(zip(coords, spans)))
    return k, nu, jnp.where(k == 0, jnp.log(r_low), 0.0)


def _valid(lam, *more):
    ok = (lam >= LAM_RANGE[0] * (1 - 1e-12)) & (lam <= LAM_RANGE[1] * (1 + 1e-12))
    for m in more:
        ok = ok & m
    return ok


def in_range(r: ArrayLike, lam: ArrayLike) -> jnp.ndarray:
    """True where the tables give the state: r > 0 and lam in :data:`LAM_RANGE`."""
    return _valid(jnp.asarray(lam, float), jnp.asarray(r, float) > 0.0)


def pull_off(lam: ArrayLike) -> jnp.ndarray:
    """Pbar_c(lam) = min Pbar [-] (models.laws.maugis_dugdale.reduced_pull_off), from its table;
    NaN outside :data:`LAM_RANGE`."""
    lam = jnp.asarray(lam, float)
    k, nu = _lam_coordinate(lam)
    value = jnp.sum(jnp.asarray(load()["pull_off"])[k] * chebyshev.basis(nu, _M), axis=-1)
    return jnp.where(_valid(lam), value, jnp.nan)


def load_ratio(load: ArrayLike, *, radius: ArrayLike, gamma: ArrayLike,
               lam: ArrayLike, pc: ArrayLike | None = None) -> jnp.ndarray:
    """r = F0/Fc [-], Fc = -Pbar_c(lam) pi w R the pull-off force [N] (w = 2 gamma);
    ``pc``: Pbar_c(lam) where the caller has it."""
    fs = contact.scales(e_star=1.0, radius=radius, gamma=gamma)[2]
    return jnp.asarray(load, float) / (-(pull_off(lam) if pc is None else pc) * fs)


def state(r: ArrayLike, lam: ArrayLike,
          pc: ArrayLike | None = None) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """(ln n, ln D, Pbar_c) [-] at load ratio r and lam (module doc), from the tables;
    NaN where r <= 0 or lam is outside :data:`LAM_RANGE`. Differentiable in both.
    ``pc``: Pbar_c(lam) where the caller has it (it is returned as given)."""
    r, lam = jnp.broadcast_arrays(jnp.asarray(r, float), jnp.asarray(lam, float))
    t = load()
    i, nu_r, off = _r_coordinate(jnp.where(r > 0.0, r, 1.0))
    j, nu_q = _lam_coordinate(lam)
    tp, tq = chebyshev.basis(nu_r, _M), chebyshev.basis(nu_q, _M)
    pick = lambda c: jnp.einsum("...a,...ab,...b->...", tp, jnp.asarray(c)[i, j], tq)
    ok = _valid(lam, r > 0.0)
    mask = lambda v: jnp.where(ok, v, jnp.nan)
    return (mask(pick(t["ln_n"]) - off), mask(pick(t["ln_d"]) - (2.0 / 3.0) * off),
            pull_off(lam) if pc is None else pc)


def contact_state(load: ArrayLike, *, radius: ArrayLike, gamma: ArrayLike,
                  lam: ArrayLike) -> tuple[jnp.ndarray, ...]:
    """(r, ln n, ln D, Pbar_c) [-] under the load F0 [N]: :func:`load_ratio` and
    :func:`state`, Pbar_c evaluated once. What the law's overlap maps read; a sampler's
    model computes it once a step and hands it to all of them (``state=``)."""
    pc = pull_off(lam)
    r = load_ratio(load, radius=radius, gamma=gamma, lam=lam, pc=pc)
    return (r, *state(r, lam, pc)[:2], pc)


def _held(state, load, radius, gamma, lam):
    return contact_state(load, radius=radius, gamma=gamma, lam=lam) if state is None \
        else state


def static_overlap(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
                   gamma: ArrayLike, lam: ArrayLike, state: tuple | None = None) -> jnp.ndarray:
    """delta0 = d_s D Pbar0^(2/3) [m] under the load F0 [N] (as
    :func:`models.laws.maugis_dugdale.static_overlap`, from the tables). ``state``: the
    :func:`contact_state` at these keywords, where the caller has it."""
    _, d_s, fs = contact.scales(e_star=e_star, radius=radius, gamma=gamma)
    pbar0 = jnp.asarray(load, float) / fs
    ln_d = _held(state, load, radius, gamma, lam)[2]
    return d_s * jnp.exp(ln_d + (2.0 / 3.0) * jnp.log(pbar0))


def overlap_from_frequency(f0: ArrayLike, load: ArrayLike, mass: ArrayLike, *,
                           radius: ArrayLike, gamma: ArrayLike, lam: ArrayLike,
                           state: tuple | None = None) -> jnp.ndarray:
    """delta0 = n F0/(m omega0^2) [m] at f0 [Hz] (as
    :func:`models.laws.maugis_dugdale.overlap_from_frequency`, from the tables; E* drops out;
    ``state`` as for :func:`static_overlap`)."""
    ln_n = _held(state, load, radius, gamma, lam)[1]
    omega2 = jnp.square(2.0 * jnp.pi * jnp.asarray(f0, float))
    return jnp.exp(ln_n) * load / (mass * omega2)


def frequency_from_overlap(delta0: ArrayLike, load: ArrayLike, mass: ArrayLike, *,
                           radius: ArrayLike, gamma: ArrayLike, lam: ArrayLike,
                           state: tuple | None = None) -> jnp.ndarray:
    """f0 = (n F0/(m delta0))^(1/2)/(2 pi) [Hz]: the inverse of
    :func:`overlap_from_frequency` (``state`` as there)."""
    ln_n = _held(state, load, radius, gamma, lam)[1]
    return jnp.sqrt(jnp.exp(ln_n) * load / (mass * jnp.asarray(delta0, float))) / (2 * jnp.pi)


def _main(argv: list[str] | None = None) -> int:
    return rebuild_cli(argv, prog="python -m beadrod.models.laws.maugis_dugdale.static",
                       description="Tabulated Maugis-Dugdale static state.", build=build,
                       path=TABLE_PATH)


if __name__ == "__main__":
    raise SystemExit(_main())
