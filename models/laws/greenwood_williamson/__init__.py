"""Greenwood-Williamson rough sphere on a flat (Greenwood-Tripp), fast enough for NUTS.

Physics (solved offline by :mod:`models.laws.greenwood_williamson.tripp`): the elastic sphere
(radius R,
combined modulus E*) presses on a Greenwood-Williamson layer of summits (density eta,
radius beta, Gaussian heights of rms sigma about their mean plane, truncated at
s_c = 6 sigma); the nominal asperity pressure deforms the bulk (Boussinesq), which is
the Greenwood-Tripp treatment (Greenwood & Williamson, Proc. R. Soc. A 295, 300 (1966);
Greenwood & Tripp, J. Appl. Mech. 34, 153 (1967); K. L. Johnson, *Contact Mechanics*
(CUP 1985), Sec. 13.4).

Parameters. The law's fitted parameters are E (through E* = E/(2 (1 - nu^2))) and the
roughness sigma [m] (the combined summit-height rms of bead and rod; prior centred on
the scene's roughness, e.g. LogNormal(log 25 nm, 0.5)). The asperity parameters are tied
by holding Johnson's mu = (8/3) eta sigma (2 R beta)^(1/2) at ``MU = 4``: with Greenwood &
Williamson's empirical eta sigma beta ~ 0.04 this is a summit radius beta =
2R (0.32/(3 mu))^2 = 11 um for the 7.9 mm bead and eta = 0.04/(sigma beta) (1.4e11 m^-2
at 25 nm), plausible for polished steel. With mu = 4 the central pressure at alpha = 0.05
is 6.8 % below Hertz, consistent with Greenwood, Johnson & Matsubara (Wear 100, 47 (1984):
"alpha < 0.05: errors of Hertz theory not likely to exceed about 7 %"). mu matters: the
summit layer's compliance scales as mu^(-2/3) (at D = 2 the offset D - e below is +0.31,
-0.42, -1.09 for mu = 1, 4, 17); other mu need a rebuilt table (``build_table(mu=...)``).

Dimensionless law. With the approach D = delta/sigma of the sphere's far field (D = 0:
the undeformed apex at the summits' mean plane) and F* = E* R^(1/2) sigma^(3/2),

    F(delta) = F* f(D) = (4/3) E* R^(1/2) eps(delta)^(3/2),   eps = sigma e(D),

one universal curve f(D) (mu fixed): the rough sphere is a Hertz contact at the
"Hertz-equivalent approach" eps(delta; sigma) [m], independent of E* and R. Johnson's
roughness parameter under a load F0 is alpha = sigma R/a0^2 = sigma/delta_H(F0) = 1/e(D0)
(delta_H the Hertz approach); the static overlap is delta0 = sigma D0 with e(D0) =
delta_H/sigma. Prior region (sigma in [1, 200] nm, E in [150, 250] GPa, F0 = 0.158 N,
R = 7.938 mm): alpha in [0.015, 4.4], D0 in [-1.3, 66]; delta0 < 0 for sigma >~ 60 nm.
Limits: D -> inf, e = D - 0.352 D^(1/3) + ... (the summit layer's compression under
the Hertz pressure), so f -> (4/3) D^(3/2) (Hertz) as sigma -> 0 at fixed delta, with a
relative deviation 0.53 (sigma/delta)^(2/3); D -> -s_c, f -> (4 pi/5) c F_{5/2}(-D)
(rigid sphere, c = mu/(2 sqrt 2)) ~ (D + s_c)^(7/2): F = 0 exactly for delta <= -s_c sigma
(``contact_edge``). F is positive below delta = 0 (the highest summits touch first).
Callers that need contact to start at 0 (unilateral convention) use delta + s_c sigma.

Table (``models/laws/greenwood_williamson/data/gw_table.npz``). Y(D) = ln f(D) - (7/2) ln(D + s_c)
(smooth, finite
at the edge) is sampled at 401 knots uniform in z = asinh((D + s_c)/2), D in [-s_c,
1e4] (spacing 0.15 at D ~ 0), by the Greenwood-Tripp solver (Richardson, 200/400 rings),
and interpolated by a quintic spline (scipy make_interp_spline, k = 5: C4). Measured
against independent solves at the midpoints of a twice finer set: |error of ln f| <=
1.3e-9. Beyond D = 1e4: e = D - o_hi (D/1e4)^p, with o_hi and p matching e's value and
slope there (C1; p = 0.34). Gradients are finite everywhere, including delta <= 0, below
the contact edge (exactly 0), and sigma -> 0 (sigma = 0 is Hertz exactly).

Backbone rung: the exact backbone tabulated in (x, ln D0'), D0' = delta0'/sigma the overlap
counted from the contact edge (:mod:`models.tables.shape_build`), within 3e-5 in Delta f/f0.

Regenerate (deterministic; a few minutes)::

    python -m beadrod.models.laws.greenwood_williamson --rebuild
"""

from __future__ import annotations

import math
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.laws import hertz
from beadrod.models.laws.greenwood_williamson.tripp import MU_DEFAULT, SUMMIT_CUTOFF
from beadrod.models.safe_math import graded_cell, horner_rows, safe_pow
from beadrod.models.tables import inverse_spline
from beadrod.models.tables.inverse_spline import solve_increasing
from beadrod.models.tables.shape_spec import ShapeTable

__all__ = ["MU", "SUMMIT_CUTOFF", "APPROACH_MAX", "TABLE_PATH", "force_scale",
           "reduced_hertz_approach", "reduced_force", "reduced_overlap", "solve_reduced_overlap",
           "reduced_overlap_from_ratio", "solve_reduced_overlap_from_ratio", "effective_approach",
           "force", "stiffness", "static_overlap", "overlap_from_frequency", "contact_edge",
           "roughness_parameter", "build_table", "inverse_tables", "load_table"]

MU = MU_DEFAULT
"""Johnson's mu = (8/3) eta sigma (2 R beta)^(1/2) of the stored table [-]."""

APPROACH_MAX = 1.0e4
"""Top of the tabulated D = delta/sigma; above it the C1 asymptotic form (module doc)."""

TABLE_PATH = pathlib.Path(__file__).with_name("data") / "gw_table.npz"

_N_KNOTS = 401
_Z_WIDTH = 2.0
_INVERSE_KNOTS = 1601
_INVERSE_EDGE = 0.01   # lowest t = D + s_c of the inverse tables (below: power-law ends)
_TABLE: dict[str, np.ndarray] | None = None


def force_scale(*, e_star: ArrayLike, radius: ArrayLike, sigma: ArrayLike) -> jnp.ndarray:
    """F* = E* R^(1/2) sigma^(3/2) [N], the force unit of f(D)."""
    return e_star * jnp.sqrt(radius) * safe_pow(sigma, 1.5)


def load_table() -> dict[str, np.ndarray]:
    """The stored table as numpy arrays (loaded once; no JAX arrays at import time)."""
    global _TABLE
    if _TABLE is None:
        with np.load(TABLE_PATH) as f:
            _TABLE = {k: f[k] for k in f.files}
    return _TABLE


def reduced_hertz_approach(approach: ArrayLike) -> jnp.ndarray:
    """e(D) = ((3/4) f(D))^(2/3) [-]: the Hertz-equivalent approach in units of sigma at
    the far-field approach D = delta/sigma [-] (any real D; 0 for D <= -s_c)."""
    tab = load_table()
    d = jnp.asarray(approach, float)
    t = d + SUMMIT_CUTOFF
    top = APPROACH_MAX + SUMMIT_CUTOFF
    # where, not clip: clip splits the gradient in half at the bounds
    tc = jnp.where(t <= top, jnp.where(t > 0.0, t, 0.0), top)
    z = jnp.arcsinh(tc / _Z_WIDTH)
    zk = np.asarray(tab["z_knots"])
    h = float(zk[1] - zk[0])
    if zk[0] != 0.0 or not np.allclose(np.diff(zk), h, rtol=1e-12, atol=0.0):
        raise ValueError("the rough-sphere table's z knots are not uniform from 0; rebuild it")
    i, dz = graded_cell(z, z / h, lambda j: j * h, zk.size - 1)
    y = horner_rows(np.ascontiguousarray(np.asarray(tab["coef"]).T), i, dz)
    e_tab = (0.75 ** (2.0 / 3.0)) * safe_pow(tc, 7.0 / 3.0) * jnp.exp(2.0 * y / 3.0)
    dh = jnp.maximum(d, APPROACH_MAX)     # the asymptotic branch sees D >= D_max only
    e_hi = dh - float(tab["offset_hi"]) * (dh / APPROACH_MAX) ** float(tab["power_hi"])
    return jnp.where(d > APPROACH_MAX, e_hi, jnp.where(t > 0.0, e_tab, 0.0))


def reduced_force(approach: ArrayLike) -> jnp.ndarray:
    """f(D) = F/F* = (4/3) e(D)^(3/2) [-] at D = delta/sigma [-]."""
    return 4.0 / 3.0 * safe_pow(reduced_hertz_approach(approach), 1.5)


def _slope(fun, x):
    return jax.jvp(fun, (x,), (jnp.ones_like(x),))


def _positive(x):
    return jnp.maximum(x, jnp.finfo(jnp.result_type(x)).tiny)


def _inverse_tables():
    tab = load_table()
    if "load_inverse.coef" not in tab:
        raise RuntimeError(f"{TABLE_PATH} lacks its inverse tables: rebuild it "
                           "(python -m beadrod.models.laws.greenwood_williamson --rebuild)")
    return ({k.split(".", 1)[1]: v for k, v in tab.items() if k.startswith("load_inverse.")},
            {k.split(".", 1)[1]: v for k, v in tab.items() if k.startswith("ratio_inverse.")})


def solve_reduced_overlap(hertz_approach: ArrayLike) -> jnp.ndarray:
    """D0 [-] with e(D0) = E0 = 1/alpha > 0 by Newton to convergence, implicit gradients
    (the reference that :func:`reduced_overlap`'s table is built from and tested against).

    e is increasing and convex (checked on the table), so Newton converges from any start
    right of the root; the start 2 E0 - e(E0) is within O(o o') of it for large E0.
    """
    e0 = jnp.asarray(hertz_approach, float)
    start = jnp.maximum(2.0 * e0 - reduced_hertz_approach(e0), 0.5 - SUMMIT_CUTOFF)
    return solve_increasing(reduced_hertz_approach, e0, jax.lax.stop_gradient(start),
                            -SUMMIT_CUTOFF)


def _hertz_ratio(approach):
    # e/e' = (2/3) F/F' (F ~ e^(3/2)); increasing because f is log-concave (table check)
    e, de = _slope(reduced_hertz_approach, approach)
    return e / _positive(de)


def solve_reduced_overlap_from_ratio(ratio: ArrayLike) -> jnp.ndarray:
    """D0 [-] with e/e'(D0) = ratio > 0 by Newton to convergence, implicit gradients (the
    reference of :func:`reduced_overlap_from_ratio`)."""
    lam = jnp.asarray(ratio, float)
    start = jax.lax.stop_gradient(jnp.maximum(lam, 0.5 - SUMMIT_CUTOFF))
    return solve_increasing(_hertz_ratio, lam, start, -SUMMIT_CUTOFF)


def _above_table(y, table, fixed_point):
    # D > D_max: e = D - o (D/D_max)^p, a contraction in D (slope o p/D_max^p D^(p-1) ~
    # 3e-4), so three fixed-point steps reach round-off; y is clamped to the table's top
    # so the branch that where() discards stays finite
    o, p = float(load_table()["offset_hi"]), float(load_table()["power_hi"])
    yc = jnp.maximum(y, float(np.exp(table["s_range"][1])))
    d = yc
    for _ in range(3):
        d = fixed_point(yc, d, o * (d / APPROACH_MAX) ** p, p)
    return d


def reduced_overlap(hertz_approach: ArrayLike) -> jnp.ndarray:
    """D0 = delta0/sigma [-] with e(D0) = E0, E0 = delta_H(F0)/sigma = 1/alpha [-] > 0:
    the tabulated inverse (``load_inverse`` in the table file: :func:`solve_reduced_overlap`
    at 801 knots uniform in ln E0, quintic spline, within 1e-12 relative in D0 + s_c,
    tests/test_greenwood_williamson.py); above D0 = D_max the asymptotic branch."""
    e0 = jnp.asarray(hertz_approach, float)
    table, _ = _inverse_tables()
    top = float(np.exp(table["end_values"][1])) - SUMMIT_CUTOFF
    d_tab = jnp.exp(inverse_spline.evaluate(table, jnp.log(_positive(e0)))) - SUMMIT_CUTOFF
    d_hi = _above_table(e0, table, lambda y, d, off, p: y + off)
    return jnp.where(d_tab > top, d_hi, d_tab)


def reduced_overlap_from_ratio(ratio: ArrayLike) -> jnp.ndarray:
    """D0 [-] with e/e'(D0) = ratio [-] > 0: the tabulated inverse (``ratio_inverse``,
    built like :func:`reduced_overlap`'s from :func:`solve_reduced_overlap_from_ratio`);
    above D_max the asymptotic branch, where e/e' = (D - o r)/(1 - o p r/D), r = (D/D_max)^p."""
    lam = jnp.asarray(ratio, float)
    _, table = _inverse_tables()
    top = float(np.exp(table["end_values"][1])) - SUMMIT_CUTOFF
    d_tab = jnp.exp(inverse_spline.evaluate(table, jnp.log(_positive(lam)))) - SUMMIT_CUTOFF
    d_hi = _above_table(lam, table, lambda y, d, off, p: y * (1.0 - off * p / d) + off)
    return jnp.where(d_tab > top, d_hi, d_tab)


def _sigma_parts(sigma):
    s = jnp.asarray(sigma, float)
    rough = s > 0.0
    return rough, jnp.where(rough, s, 1.0)


def effective_approach(delta: ArrayLike, *, sigma: ArrayLike) -> jnp.ndarray:
    """eps = sigma e(delta/sigma) [m]: the Hertz approach giving the same force as the rough
    contact at far-field approach delta [m]; sigma [m] >= 0 (sigma = 0: max(delta, 0))."""
    d = jnp.asarray(delta, float)
    rough, s = _sigma_parts(sigma)
    return jnp.where(rough, s * reduced_hertz_approach(d / s), jnp.maximum(d, 0.0))


def force(delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
          sigma: ArrayLike) -> jnp.ndarray:
    """F = (4/3) E* R^(1/2) eps(delta; sigma)^(3/2) = F* f(delta/sigma) [N], defined for all
    real delta [m] (the sphere's far-field approach from the summits' mean plane); 0 for
    delta <= -6 sigma. e_star [Pa], radius [m], sigma [m] (rms summit height)."""
    eps = effective_approach(delta, sigma=sigma)
    return hertz.stiffness_constant(e_star=e_star, radius=radius) * safe_pow(eps, 1.5)


def stiffness(delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
              sigma: ArrayLike) -> jnp.ndarray:
    """Tangent stiffness K = dF/d delta = 2 E* R^(1/2) eps^(1/2) d eps/d delta [N/m]
    (forward-mode autodiff of :func:`force`, elementwise in delta)."""
    fun = lambda x: force(x, e_star=e_star, radius=radius, sigma=sigma)
    return _slope(fun, jnp.asarray(delta, float))[1]


def static_overlap(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
                   sigma: ArrayLike) -> jnp.ndarray:
    """delta0 [m] with F(delta0) = load [N] (> 0): sigma D0(delta_H/sigma), delta_H the
    Hertz overlap under the load (models.laws.hertz.static_overlap); implicit gradients."""
    dh = hertz.static_overlap(load, e_star=e_star, radius=radius)
    rough, s = _sigma_parts(sigma)
    return jnp.where(rough, s * reduced_overlap(dh / s), dh)


def overlap_from_frequency(f0: ArrayLike, load: ArrayLike, mass: ArrayLike, *,
                           sigma: ArrayLike) -> jnp.ndarray:
    """delta0 [m] that a measured linear resonance f0 [Hz] implies under load F0 [N] on a
    bead of mass m [kg], for stiffness-scale scatter between protocols (F_p = s_p F):
    F/F' = F0/(m omega0^2) at delta0, i.e. e/e'(D0) = (3/2) F0/(m omega0^2 sigma).
    Independent of E* and R, like Hertz's 3 F0/(2 m omega0^2) (its sigma -> 0 limit)."""
    ratio = load / (mass * jnp.square(2.0 * jnp.pi * jnp.asarray(f0, float)))
    rough, s = _sigma_parts(sigma)
    d0 = reduced_overlap_from_ratio(1.5 * ratio / s)
    return jnp.where(rough, s * d0, 1.5 * ratio)


def contact_edge(*, sigma: ArrayLike) -> jnp.ndarray:
    """-s_c sigma [m]: below this approach no summit touches and F = 0 exactly."""
    return -SUMMIT_CUTOFF * jnp.asarray(sigma, float)


def roughness_parameter(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike,
                        sigma: ArrayLike) -> jnp.ndarray:
    """Johnson's alpha = sigma R/a0^2 = sigma/delta_H(F0) [-] (Johnson 1985, Sec. 13.4)."""
    return sigma / hertz.static_overlap(load, e_star=e_star, radius=radius)


def build_table(mu: float = MU, n_rings: int = 200) -> dict[str, np.ndarray]:
    """Solve Greenwood-Tripp at the knots and fit the quintic spline (deterministic)."""
    from scipy.interpolate import make_interp_spline

    from beadrod.models.laws.greenwood_williamson.tripp import load_approach

    z = np.linspace(0.0, np.arcsinh((APPROACH_MAX + SUMMIT_CUTOFF) / _Z_WIDTH), _N_KNOTS)
    t = _Z_WIDTH * np.sinh(z)
    t[-1] = APPROACH_MAX + SUMMIT_CUTOFF
    f = load_approach(t[1:] - SUMMIT_CUTOFF, mu=mu, n_rings=n_rings)
    y = np.empty_like(z)
    y[1:] = np.log(f) - 3.5 * np.log(t[1:])
    # the edge: f -> (4 pi/5) c F_{5/2}(s_c - t), F_{5/2}(s_c - t) -> phi(s_c) t^(7/2)/(7/2)
    c = mu / (2.0 * np.sqrt(2.0))
    y[0] = np.log(0.8 * np.pi * c * np.exp(-0.5 * SUMMIT_CUTOFF**2) / np.sqrt(2.0 * np.pi)
                  / 3.5)
    spline = make_interp_spline(z, y, k=5)
    # local Taylor coefficients in each uniform cell (right derivatives at its left end;
    # a cell lies inside one polynomial piece), highest power first
    coef = np.stack([spline(z[:-1], nu=k) / math.factorial(k) for k in range(5, -1, -1)])
    # value and slope of e at D_max fix the asymptotic branch e = D - o (D/D_max)^p
    e_hi = 0.75 ** (2.0 / 3.0) * t[-1] ** (7.0 / 3.0) * np.exp(2.0 * y[-1] / 3.0)
    de_dd = e_hi * (7.0 / (3.0 * t[-1]) + 2.0 / 3.0 * spline(z[-1], nu=1)
                    / np.hypot(t[-1], _Z_WIDTH))
    offset = APPROACH_MAX - e_hi
    out = {"z_knots": z, "y_knots": y, "coef": coef, "offset_hi": np.asarray(offset),
           "power_hi": np.asarray((1.0 - de_dd) * APPROACH_MAX / offset),
           "mu": np.asarray(mu), "summit_cutoff": np.asarray(SUMMIT_CUTOFF)}
    out.update(inverse_tables(out))
    return out


def inverse_tables(forward: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The tabulated inverses of the forward table ``forward`` (keys 'load_inverse.*' and
    'ratio_inverse.*'): :func:`solve_reduced_overlap` and
    :func:`solve_reduced_overlap_from_ratio` on knots uniform in ln E0 (ln ratio) from
    t = D + s_c = 0.01 to D = D_max (:func:`models.tables.inverse_spline.build`)."""
    global _TABLE
    saved, _TABLE = _TABLE, forward   # the solves read the module's table
    try:
        ends = jnp.asarray([_INVERSE_EDGE - SUMMIT_CUTOFF, APPROACH_MAX])
        out = {}
        for name, fun, solve in (("load_inverse", reduced_hertz_approach, solve_reduced_overlap),
                                 ("ratio_inverse", _hertz_ratio,
                                  solve_reduced_overlap_from_ratio)):
            s_lo, s_hi = (float(v) for v in jnp.log(fun(ends)))
            fast = jax.jit(solve)
            tab = inverse_spline.build(
                lambda s, f=fast: np.log(np.asarray(f(jnp.exp(jnp.asarray(s)))) + SUMMIT_CUTOFF),
                s_lo, s_hi, _INVERSE_KNOTS)
            out.update({f"{name}.{k}": v for k, v in tab.items()})
        return out
    finally:
        _TABLE = saved


MIN_REDUCED_OVERLAP = 3.0
"""Smallest D0' = delta0'/sigma [-] (overlap from the contact edge over sigma) at which
the law is used. A Greenwood-Williamson layer is a continuous summit density, so it needs
summits in contact: their expected number under the sphere is
N(D0') = 2 pi R eta sigma int_{6-D0'}^{6} [Phi_c(s) - Phi_c(6)] ds, with eta sigma beta =
0.04 and beta fixed by mu (the module doc), which makes N independent of sigma and R:
N = 15 at D0' = 5, 1.5 at 4, 0.07 at 3, 1e-4 at 1.5 (tests/test_greenwood_williamson.py).
Below 3 not one summit in ten would touch the bead: no contact for this law to describe
(a fit there once rested the bead on 1e-5 summits, 54 nats above its physical mode)."""
__all__ += ["MIN_REDUCED_OVERLAP"]


HERTZ_DECAY = 0.8
"""k [-] in the law's approach to Hertz's backbone as D0' = delta0'/sigma grows, ~ D0'^-k,
used past its table's end D0' = 1e4 (models.tables.shape_read.backbone_fast). Measured with
the generic backbone, paper's scene (x = 2): 3.3e-4, 5.0e-5, 8.8e-6 at D0' ~ 1e4, 1e5, 1e6
(k = 0.82, then 0.76: not a clean power; 0.8 between). Carried on from the table's end
the backbone stays within 3e-6 of the generic one at D0' = 1e5, a tenth of the table's
stated error (tests/test_shape_tables.py)."""
__all__ += ["HERTZ_DECAY"]



def _table_kw(d0e):
    # the paper's bead with sigma set so that the overlap counted from the contact edge is
    # d0e sigma
    load, radius, e_star = 0.158, 7.938e-3, 1.2e11
    d_h = hertz.static_overlap(load, e_star=e_star, radius=radius)
    sigma = d_h / reduced_hertz_approach(jnp.asarray(d0e, float) - SUMMIT_CUTOFF)
    return {"load": load, "radius": radius, "e_star": e_star, "mass": 1.0,
            "roughness_rms": sigma, "roughness_factor": 1.0}


TABLE = ShapeTable(
    _table_kw, float(np.log(1.5)), float(np.log(1e4)),
    held=("D0' = delta0'/sigma > 1e4 is roughness below 1e-4 of the overlap, yet the table's "
          "end stands 3.2e-4 from Hertz's backbone (carried on: HERTZ_DECAY); D0' < 1.5 is a "
          "load carried by the summits above 4.5 sigma alone (sigma > ~10x the paper's "
          "roughness)"),
    # D0 = D0' - 6 ~ -1 (D0' 4-16): the load passes from the summits' Gaussian tail to
    # the Hertz-like bulk and the backbone turns within ~0.3 in p; one 32-node
    # interpolant over the whole range converges algebraically (x_c to 3e-4), one per
    # piece spectrally (x_c to 1e-7)
    p_breaks=(float(np.log(4.0)), float(np.log(16.0))), m_pieces=(16, 24, 16),
    # its D0' differs per protocol in a fit: evaluated on Hermite cells in p (cell
    # widths 0.04, 0.03, 0.08: within 3e-7 of the interpolant; tables.hermite_cells)
    p_cells=(24, 48, 80),
    # the summits' force vanishes smoothly at the contact edge: C1 at x_c
    kink_c1=True)
"""The backbone table's specification (:mod:`beadrod.models.tables.shape_build`). The
sphere is one universal curve F = F* f(D) in D = delta/sigma, so its restoring force depends
on D0' = delta0'/sigma alone, delta0' the overlap counted from the contact edge -6 sigma
(p = ln D0'). Three pieces in p, because one interpolant over the whole range cannot follow
the knee at D0 = D0' - 6 ~ -1. Stated error 3e-5 in Delta f/f0 against the generic exact
backbone (tests/test_shape_tables.py)."""
__all__ += ["TABLE"]


def _law():
    from beadrod.models.law import (
        YOUNG,
        ContactLaw,
        Param,
        Physics,
        Presentation,
        Prior,
        SamplerHints,
    )
    from beadrod.models.tables.shape_read import backbone_fast, in_table

    factor = Param(
        "roughness_factor", "-", r"$\sigma/\sigma_\mathrm{scene}$", Prior("lognormal", 1.0, 0.7),
        "Summit-height rms over the scene's roughness rms (sigma = factor * roughness_rms). "
        "Prior LogNormal(median 1, sd of log 0.7): centred on the measured roughness (25 nm "
        "for the paper's bead), a factor of 8 either way at 3 sd (summit and surface rms "
        "differ, and a profilometer's band is not the contact's).")

    def sigma(kw):
        return kw["roughness_rms"] * kw["roughness_factor"]

    def reduced(delta0, kw):
        # delta0'/sigma; an array division, so that sigma = 0 (a smooth sphere, the
        # Hertz limit) gives inf, outside the table, where the generic path takes over
        # (plain floats from the command line raised ZeroDivisionError)
        return jnp.asarray(delta0, float) / sigma(kw)

    # the overlap delta' is counted from the contact edge -6 sigma (the outermost summits),
    # so the law is unilateral in delta' as models.ladder.generic expects; F/F' and the shape
    # are unchanged by the shift
    def _force(delta, **kw):
        s = sigma(kw)
        return force(delta - SUMMIT_CUTOFF * s, e_star=kw["e_star"], radius=kw["radius"],
                     sigma=s)

    def _overlap(**kw):
        s = sigma(kw)
        return static_overlap(kw["load"], e_star=kw["e_star"], radius=kw["radius"],
                              sigma=s) + SUMMIT_CUTOFF * s

    def _overlap_f0(f0, **kw):
        s = sigma(kw)
        return overlap_from_frequency(f0, kw["load"], kw["mass"], sigma=s) + SUMMIT_CUTOFF * s

    def _frequency(delta0, **kw):
        # the inverse of _overlap_f0 (stiffness-scale scatter, as models.ladder.generic's)
        from beadrod.models.ladder.generic import frequency_of_force

        return frequency_of_force(lambda x: _force(x, **kw), delta0, load=kw["load"],
                                  mass=kw["mass"])

    return ContactLaw(
        name="greenwood_williamson",
        params=(YOUNG, factor),
        physics=Physics(
            force=_force, static_overlap=_overlap,
            # the protocols scatter by the elastic scale E* R^(1/2) (F/F' does not depend on
            # it)
            overlap_from_frequency=_overlap_f0, frequency_from_overlap=_frequency,
            shifts={"backbone": lambda x, *, delta0, **kw: backbone_fast(
                "greenwood_williamson", x, reduced(delta0, kw), decay=HERTZ_DECAY)},
            # the law holds where summits carry the load (MIN_REDUCED_OVERLAP) and the table
            # covers the point (shape_backbone.in_table); the inference counts no point
            # outside
            domains={"backbone": lambda x, *, delta0, **kw: in_table(
                "greenwood_williamson", x, reduced(delta0, kw), decay=HERTZ_DECAY)
                & (reduced(delta0, kw) >= MIN_REDUCED_OVERLAP)},
            table=TABLE,
        ),
        presentation=Presentation(
            label="rough sphere (Greenwood-Williamson)", color="#999933",
            reference=("Greenwood & Williamson 1966; Greenwood & Tripp 1967; "
                       "Johnson 1985 Sec. 13.4"),
            description=("elastic sphere on a Greenwood-Williamson summit layer (Gaussian "
                         f"heights of rms sigma, Johnson's mu = {MU:g}); overlap counted from "
                         "the outermost summits. Backbone rung: a table in "
                         "(x, ln delta0'/sigma), three Chebyshev pieces, within 3e-5 in "
                         "Delta f/f0 of the exact backbone (models.tables.shape_build; "
                         "measured at most 1.1e-5). Used where "
                         f"delta0'/sigma >= {MIN_REDUCED_OVERLAP:g} (0.07 summits expected in "
                         "contact there, 1.5 at 4); the fits count no point below"),
            in_default_comparison=True,
        ),
        # relative fit time (models.law.SamplerHints.cost): tabulated load-approach integral
        # and two-parameter backbone table
        sampler=SamplerHints(cost=3.0),
    )


LAW = _law()
"""The Greenwood-Williamson rough-sphere law (:class:`models.law.ContactLaw`)."""
__all__ += ["LAW"]
