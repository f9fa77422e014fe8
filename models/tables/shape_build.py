"""Tabulated exact backbones of the laws with one or two shape parameters (JKR, DMT,
Greenwood-Williamson, Maugis-Dugdale).

Why one shape parameter is enough. In the relative coordinate q = delta/delta0 - 1 the
backbone depends only on the restoring force P'(q) = [F(delta0 (1+q)) - F0]/(K0 delta0)
and the flight acceleration F0/(K0 delta0) (:mod:`models.ladder.generic`):

* JKR is universal in Maugis' reduced units (F/Fc against delta/delta_c, Fc = 3 pi gamma
  R): at a given load P' depends on r = F0/Fc alone (p = ln r);
* DMT's P' is Hertz's inside contact, (2/3)((1+q)^(3/2) - 1); only its flight
  acceleration (2/3) F0/(F0 + Fc), Fc = 4 pi gamma R, depends on r = F0/Fc (p = ln r);
* the Greenwood-Williamson sphere is one universal curve F = F* f(D) in D = delta/sigma
  (models.laws.greenwood_williamson), so P' depends on D0' = delta0'/sigma alone, delta0' the
  overlap counted from the contact edge -6 sigma (p = ln D0').

E* drops out of all three (the tests check the invariance). The tables are built by
:mod:`models.tables.surrogate` (the tool of the power-law table) from the generic exact backbone
of each law's force. Outside a law's p range the value is held at the end (each entry of
:data:`TABLES` says what that means physically); x beyond X_MAX = 2 is held too. Fits
never use a held value (below p_lo, above p_hi, beyond X_MAX): the laws' domains
(:func:`models.tables.shape_read.in_table`) give such points zero likelihood, or the law
carries its table past p_hi as it approaches Hertz's backbone (its ``HERTZ_DECAY``). JKR and
DMT contact is taken to part at delta = 0 (where the approach branch forms it; the
snap-off hysteresis is a loss, not a stiffness). Errors against the generic exact backbone
(tests/test_shape_tables.py): JKR and DMT within 1e-5 in Delta f/f0 (measured 7e-6),
except in the 0.01 of x just past the contact-loss corner x_c, where the adhesive laws'
backbone turns by up to 30x in slope (:mod:`models.tables.surrogate`, ``kink_c1``): there within
1e-4 (measured 5e-5, near F0/Fc = 20, where the turn is sharpest against the knots).

Maugis-Dugdale: two shape coordinates, p = ln(F0/Fc) with Fc its pull-off force, and
q = ln lam in [ln 0.1, ln 100] (20 Chebyshev nodes in q; models.tables.surrogate). Stated error
as for JKR and DMT: 1e-5 away from the corner, 1e-4 in the 0.01 past x_c. Measured on 240
random (F0/Fc, lam, x) (x thirds in [0, 0.8], [0.8, 1], [1, 2]) and on 36 (F0/Fc, lam) x 8
offsets from x_c: at most 1.7e-6 away from the corner (2e-8 below x = 0.8), 4.8e-5 at
1e-3 past it (F0/Fc = 20); the same at every lam.

Greenwood-Williamson: three pieces in p (D0' in [1.5, 4], [4, 16], [16, 1e4]; 16, 24
and 16 Chebyshev nodes), because one interpolant over the whole range cannot follow the
knee at D0 = D0' - 6 ~ -1; stated error 3e-5 in Delta f/f0 (tested). Measured on 100 D0' x
4 amplitudes (0.3, 0.8, 0.95, 1.5) against the 48-node exact backbone: at most 1.1e-5, at
x = 0.8 near D0' = 40, where the corner of Hertz contact loss (smoothed over sigma, at
q = -1 + 6/D0') crosses the contact arc as p changes; <= 1.5e-7 in the two lower pieces
and at the other amplitudes.

This module builds the tables from the laws (it imports them); the laws' backbone rungs
read them through :mod:`models.tables.shape_read` (:func:`backbone_fast`, :func:`load_table`,
re-exported here), which imports no law: the dependency runs one way.

Regenerate (deterministic; tens of minutes per law)::

    python -m beadrod.models.tables.shape_build --rebuild [--law
    jkr|dmt|greenwood_williamson|maugis_dugdale]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.laws import dmt, greenwood_williamson, hertz, jkr, maugis_dugdale
from beadrod.models.tables import surrogate
from beadrod.models.tables.rebuild import rebuild_cli
from beadrod.models.tables.shape_read import TABLE_PATH, X_MAX, backbone_fast, load_table

__all__ = ["X_MAX", "TABLE_PATH", "TABLES", "ShapeTable", "backbone_fast", "exact_backbone",
           "load_table", "build_table", "spec"]

# table grid and the orbit rule used to build it: 24 Gauss nodes are spectrally accurate on
# the contact arc (the flight arc's graded rule is fixed); the tests measure the table
# against the 48-node exact backbone
_M_CHEB, _N_KNOTS, _BUILD_NODES = 16, 48, 24


def _jkr_kw(r, per_gamma):
    radius, load = 0.01, 1.0
    return {"load": load, "radius": radius, "e_star": 1e11, "mass": 1.0,
            "gamma": load / (per_gamma * radius * jnp.asarray(r, float))}


def _gw_kw(d0e):
    load, radius, e_star = 0.158, 7.938e-3, 1.2e11
    d_h = hertz.static_overlap(load, e_star=e_star, radius=radius)
    gw = greenwood_williamson
    sigma = d_h / gw.reduced_hertz_approach(jnp.asarray(d0e, float) - gw.SUMMIT_CUTOFF)
    return {"load": load, "radius": radius, "e_star": e_star, "mass": 1.0,
            "roughness_rms": sigma, "roughness_factor": 1.0}


def _md_kw(r, lam):
    # units with K = 4 E*/3 = 1, R = 1, pi w R = 1 (so a_s = d_s = F_s = 1): the load is
    # r times the pull-off force -Pbar_c(lam)
    lam = jnp.asarray(lam, float)
    return {"load": -jnp.asarray(r, float) * maugis_dugdale.reduced_pull_off(lam), "radius": 1.0,
            "e_star": 0.75, "gamma": 0.5 / np.pi, "lam": lam, "mass": 1.0}


@dataclass(frozen=True)
class ShapeTable:
    """One law's table: ``law`` (module name holding LAW), ``reference_kw(s)`` the resolved
    keywords of a contact whose shape parameter is s = exp(p), p in [p_lo, p_hi]. A law
    whose shape has a second coordinate q = ln t (t in exp(q_range), ``m_q`` Chebyshev
    nodes) takes it as ``reference_kw(s, t)``."""

    law: str
    reference_kw: Callable
    p_lo: float
    p_hi: float
    held: str
    m_cheb: int = _M_CHEB
    p_breaks: tuple[float, ...] = ()
    m_pieces: tuple[int, ...] = ()
    p_cells: tuple[int, ...] = ()
    q_range: tuple[float, float] | None = None
    m_q: int = 0
    kink_c1: bool = False  # the adhesive laws' backbone has a corner at x_c (surrogate doc)

    def kw(self, s, t=None) -> dict:
        """The reference contact's keywords at shape parameter s (and t, the second one,
        where the table has it)."""
        return self.reference_kw(s) if self.q_range is None else self.reference_kw(s, t)


TABLES: dict[str, ShapeTable] = {
    "jkr": ShapeTable("jkr", lambda r: _jkr_kw(r, 3.0 * np.pi), float(np.log(0.3)),
                      float(np.log(1000.0)),
                      "r = F0/Fc > 1000 is adhesion below 0.1 % of the load, yet the table's end "
                      "stands 2e-4 from Hertz's backbone (carried on as 1/r: "
                      "jkr.HERTZ_DECAY); r < 0.3 is gamma > 7 J/m^2 for the paper's bead"),
    "dmt": ShapeTable("dmt", lambda r: _jkr_kw(r, 4.0 * np.pi), float(np.log(0.3)),
                      float(np.log(1000.0)), "as for JKR, with Fc = 4 pi gamma R"),
    "greenwood_williamson": ShapeTable(
        "greenwood_williamson", _gw_kw, float(np.log(1.5)), float(np.log(1e4)),
        "D0' = delta0'/sigma > 1e4 is roughness below 1e-4 of the overlap, yet the table's end "
        "stands 3.2e-4 from Hertz's backbone (carried on: HERTZ_DECAY); D0' < 1.5 "
        "is a load carried by the summits above 4.5 sigma alone (sigma > ~10x the paper's "
        "roughness)",
        # D0 = D0' - 6 ~ -1 (D0' 4-16): the load passes from the summits' Gaussian tail to
        # the Hertz-like bulk and the backbone turns within ~0.3 in p; one 32-node
        # interpolant over the whole range converges algebraically (x_c to 3e-4), one per
        # piece spectrally (x_c to 1e-7)
        p_breaks=(float(np.log(4.0)), float(np.log(16.0))), m_pieces=(16, 24, 16),
        # its D0' differs per protocol in a fit: evaluated on Hermite cells in p (cell
        # widths 0.04, 0.03, 0.08: within 3e-7 of the interpolant; models.tables.hermite_cells)
        p_cells=(24, 48, 80),
        # the summits' force vanishes smoothly at the contact edge: C1 at x_c
        kink_c1=True),
    "maugis_dugdale": ShapeTable(
        "maugis_dugdale", _md_kw, float(np.log(0.3)), float(np.log(1000.0)),
        "as for JKR, with Fc the Maugis-Dugdale pull-off force (3 pi gamma R to 4 pi gamma R); "
        "lambda outside [0.1, 100] (the prior's range) is outside the table",
        # the second coordinate, ln lambda: the shape moves from DMT-like to JKR-like
        # across lambda ~ 0.3-3; its Chebyshev terms fall to ~1e-7 of S by the 16th
        q_range=(float(np.log(0.1)), float(np.log(100.0))), m_q=20),
}
"""The tabulated laws and their shape coordinates."""
_EXACT: dict[tuple[str, int], object] = {}


# the modules holding each table's LAW, by ShapeTable.law
_LAW_MODULES = {"jkr": jkr, "dmt": dmt, "greenwood_williamson": greenwood_williamson,
                "maugis_dugdale": maugis_dugdale}


def _law(name):
    return _LAW_MODULES[TABLES[name].law].LAW


def exact_backbone(name: str, x: ArrayLike, s: ArrayLike, nodes: int = 48,
                   t: ArrayLike = 1.0) -> jnp.ndarray:
    """Exact backbone Delta f/f0 of law ``name`` at x and shape parameter s (and t, the
    second one, where the law has it): the generic quadrature of its restoring force."""
    from beadrod.models.ladder.generic import backbone_shift

    if (name, nodes) not in _EXACT:
        law, tab = _law(name), TABLES[name]

        def one(xi, si, ti):
            kw = tab.kw(si, ti)
            return backbone_shift(law, xi, delta0=law.overlap(**kw), nodes=nodes, **kw)

        _EXACT[(name, nodes)] = jax.jit(jax.vmap(one))
    x, s, t = jnp.broadcast_arrays(*(jnp.asarray(v, float) for v in (x, s, t)))
    return _EXACT[(name, nodes)](x.ravel(), s.ravel(), t.ravel()).reshape(x.shape)


def spec(name: str) -> surrogate.BackboneSpec:
    """The surrogate specification of law ``name`` (p = ln s)."""
    from beadrod.models.ladder.generic import contact_loss_onset, lindstedt_coefficient

    tab = TABLES[name]

    def ref(p, q):
        return tab.kw(jnp.exp(p), jnp.exp(q))

    @jax.jit
    @jax.vmap
    def kink(p, q):
        law, kw = _law(name), ref(p, q)
        return contact_loss_onset(law, delta0=law.overlap(**kw), **kw)

    @jax.jit
    @jax.vmap
    def lindstedt(p, q):
        law, kw = _law(name), ref(p, q)
        return lindstedt_coefficient(law, delta0=law.overlap(**kw), **kw)

    def zero(p, q):   # a table without a second coordinate passes none: any value serves
        return np.zeros_like(p) if q is None else q

    def exact(x, p, xc, q=None):
        q = zero(p, q)
        out = np.empty_like(x)
        size = 128  # bounded memory per batch; the last batch is padded (one compile)
        for i in range(0, x.size, size):
            n = min(size, x.size - i)
            xs, ps, qs = (np.resize(a[i:i + size], size) for a in (x, p, q))
            out[i:i + n] = np.asarray(exact_backbone(name, xs, np.exp(ps),
                                                     nodes=_BUILD_NODES, t=np.exp(qs)))[:n]
        return out

    return surrogate.BackboneSpec(
        p_lo=tab.p_lo, p_hi=tab.p_hi, exact=exact,
        kink=lambda p, q=None: tuple(np.asarray(v) for v in kink(jnp.asarray(p),
                                                                 jnp.asarray(zero(p, q)))),
        lindstedt=lambda p, q=None: np.asarray(lindstedt(jnp.asarray(p),
                                                         jnp.asarray(zero(p, q)))),
        x_max=X_MAX, m_cheb=tab.m_cheb, n_knots=_N_KNOTS, p_breaks=tab.p_breaks,
        m_pieces=tab.m_pieces, p_cells=tab.p_cells, q_range=tab.q_range, m_q=tab.m_q,
        kink_c1=tab.kink_c1)


def build_table(names: tuple[str, ...] = tuple(TABLES)) -> dict[str, np.ndarray]:
    """The tables of ``names`` (keys prefixed 'NAME.'), merged into the stored ones."""
    out = {}
    if TABLE_PATH.exists():
        with np.load(TABLE_PATH) as f:
            out = {k: f[k] for k in f.files if k.split(".", 1)[0] not in names}
    for name in names:
        for k, v in surrogate.build(spec(name)).items():
            out[f"{name}.{k}"] = v
    return out


def _main(argv: list[str] | None = None) -> int:
    return rebuild_cli(argv, prog="python -m beadrod.models.tables.shape_build",
                       description="Tabulated backbones of the one-shape-parameter laws.",
                       build=build_table, path=TABLE_PATH, parts=tuple(TABLES))


if __name__ == "__main__":
    raise SystemExit(_main())
