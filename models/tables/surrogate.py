"""The tool that builds fast backbone surrogates for one-shape-parameter laws.

A law whose dimensionless backbone Delta f/f0 = S(x; p) depends on one shape parameter p
(the power law's n; the JKR and DMT load ratio F0/Fc, as log F0/Fc) gets a table built
here from its exact backbone, fast enough for NUTS.
The power-law table of :mod:`models.tables.powerlaw_backbone` and the tables of
:mod:`models.tables.shape_build` (JKR, DMT, Greenwood-Williamson) are built and evaluated by this
one tool.

Structure (measured on the power law, see models.tables.powerlaw_backbone): contact loss starts at
the first-harmonic amplitude x_c(p), where S is C1 but not C2. The x axis is split there,
with kink-aligned coordinates u = x/x_c(p) (contact) and v = (x - x_c)/(x_max - x_c)
(flight). Below x_c, S = pre(p) x^2 Q(u, p) with Q smooth and Q(0, p) the Lindstedt
coefficient divided by pre(p) (exact at small x). In each region a cubic spline (C2) in
u (resp. v) on 64 knots graded towards the kink (u_i = 1 - (1 - i/63)^2, v_i = (i/63)^2),
tensor product with a degree-23 Chebyshev interpolant in p on the 24 Chebyshev-Gauss
nodes of [p_lo, p_hi]; x_c(p) is a Chebyshev interpolant on the same nodes. The contact
spline is not-a-knot; the flight spline is clamped at v = 0 to the contact spline's slope
there, so the surrogate is C1 across x_c like the exact backbone.

Adhesive laws (``kink_c1=False``). Where the force jumps at the contact edge (JKR, DMT,
Maugis-Dugdale: the bead leaves with a finite pull), the backbone is continuous at x_c but
not C1: just past the onset both x and S move like sqrt(q_max - q_c) of the orbit's turning
point, and S(x) leaves with a slope of its own (JKR at F0/Fc = 0.6: dS/dx -0.09 in contact,
-2.7 in flight, measured with models.ladder.generic.backbone_shift). S(x) is smooth on each side,
so the flight spline then starts not-a-knot instead of clamped: clamping it to the contact
slope would err by up to 2.5e-2 in Delta f/f0 within 0.02 of x_c.

Pieces in p. A law whose backbone varies steeply in one stretch of its p range (the
Greenwood-Williamson sphere where the load passes from the summits' Gaussian tail to the
Hertz-like bulk, D0 = delta0/sigma ~ -1) sets ``p_breaks``: each piece [p_k, p_k+1] gets
its own Chebyshev interpolant (``m_pieces`` nodes, zero-padded to the largest), stored with
a leading piece axis and the edges as ``p_edges``. The surrogate is then continuous in p
only to its stated error (a jump of that size at a break; gradients stay finite). Without
breaks the table is the single interpolant above, unchanged.

A second shape coordinate. A law whose shape depends on two numbers (Maugis-Dugdale: the
load ratio and Maugis' lambda) sets ``q_range`` and ``m_q``: the table above is built at
each of ``m_q`` Chebyshev-Gauss nodes of q and every array gains a last axis over them;
the spline and kink coefficients become Chebyshev interpolants in q on that axis (a tensor
product in p and q). Such a table is read at one (p, q) for all points, the sampler's case
(:mod:`models.tables.patches_2d`: local patches in (p, q) resampled from that interpolant).

Cells in p. A table whose p differs from point to point in a fit (one per protocol) can set
``p_cells``: it is then evaluated on cubic Hermite cells in p resampled from its
Chebyshev interpolant (:mod:`models.tables.hermite_cells`: 16 coefficients gathered per point
instead
of 96; the resampling's error is measured against the interpolant in the tests).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.models.safe_math import materialize
from beadrod.models.tables import chebyshev, one_shape, patches_2d
from beadrod.models.tables import hermite_cells as p_cells

__all__ = ["X_MAX", "BackboneSpec", "build", "evaluate", "within_amplitude", "chebyshev_nodes",
           "chebyshev_basis", "kink_amplitude", "to_chebyshev", "spline_coefficients"]

chebyshev_basis = chebyshev.basis
"""T_0..T_{m-1}(nu) (:func:`models.tables.chebyshev.basis`)."""
to_chebyshev = chebyshev.to_chebyshev
"""Values on Chebyshev-Gauss nodes -> coefficients
(:func:`models.tables.chebyshev.to_chebyshev`)."""

X_MAX = 2.0
"""The largest x = delta_a/delta0 [-] every backbone table covers (the bead flies over
twice its overlap); the one definition the tables and their domains share."""


@dataclass(frozen=True)
class BackboneSpec:
    """What the tool needs of a law's exact backbone.

    ``exact(x, p, xc)``: exact S at arrays x, p (x_c(p) given for rules that refine next
    to the kink); ``kink(p)``: (x_c, S_c) at the onset of contact loss; ``lindstedt(p)``:
    c(p) in S = c x^2 + O(x^4); ``prefactor(p)``: pre(p) (n - 1 for the power law, whose
    shift vanishes identically at n = 1; 1 otherwise). With a second shape coordinate
    (``q_range``, ``m_q`` nodes; module doc) ``exact``, ``kink`` and ``lindstedt`` take
    the array q as a last argument. ``kink_c1``: whether S is C1 at x_c (False for a
    force that jumps at the contact edge; module doc).
    """

    p_lo: float
    p_hi: float
    exact: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    kink: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
    lindstedt: Callable[[np.ndarray], np.ndarray]
    prefactor: Callable[[np.ndarray], np.ndarray] = lambda p: np.ones_like(p)
    x_max: float = 2.0
    m_cheb: int = 24
    n_knots: int = 64
    p_breaks: tuple[float, ...] = ()
    m_pieces: tuple[int, ...] = ()
    p_cells: tuple[int, ...] = ()
    q_range: tuple[float, float] | None = None
    m_q: int = 0
    kink_c1: bool = True


def chebyshev_nodes(spec: BackboneSpec) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev-Gauss nodes nu_j in (-1, 1) and p_j (no node at the domain ends)."""
    return chebyshev.gauss_nodes(spec.p_lo, spec.p_hi, spec.m_cheb)


def _knots(k: int) -> tuple[np.ndarray, np.ndarray]:
    s = np.linspace(0.0, 1.0, k)
    return p_cells.contact_knot(s), p_cells.flight_knot(s)


def spline_coefficients(knots: np.ndarray, data: np.ndarray,
                        start_slope: np.ndarray | None = None) -> np.ndarray:
    """Cubic spline of data (knots, m) -> local power coefficients (4, k-1, m); not-a-knot
    ends, or a clamped first derivative ``start_slope`` (m,) at the first knot."""
    from scipy.interpolate import CubicSpline

    bc = "not-a-knot" if start_slope is None else ((1, start_slope), "not-a-knot")
    return CubicSpline(knots, data, axis=0, bc_type=bc).c


_CHEB_KEYS = ("xc_cheb", "coef_contact", "coef_flight")


def build(spec: BackboneSpec) -> dict[str, np.ndarray]:
    """Evaluate the exact backbone on the grid and fit the splines (deterministic); with
    ``p_breaks``, one interpolant per piece; with ``q_range``, a tensor product in (p, q)
    (module doc)."""
    if spec.q_range is not None:
        return _build_two(spec)
    if spec.p_breaks:
        out = _build_pieces(spec)
    else:
        out = _build_single(spec)
    if spec.p_cells:  # evaluated on Hermite cells in p (models.tables.hermite_cells)
        out["p_cells"] = np.asarray(spec.p_cells, int)
    return out


def _build_single(spec: BackboneSpec) -> dict[str, np.ndarray]:
    nu, p = chebyshev_nodes(spec)
    uk, vk = _knots(spec.n_knots)
    xc, sc = (np.asarray(a, float) for a in spec.kink(p))
    pre = np.asarray(spec.prefactor(p), float)
    xm = spec.x_max
    qa = np.empty((uk.size, p.size))
    qa[0] = np.asarray(spec.lindstedt(p)) / pre
    qa[-1] = sc / (pre * xc**2)
    uu, pp = np.meshgrid(uk[1:-1], p, indexing="ij")
    xcb = np.broadcast_to(xc, pp.shape)
    x = uu * xcb
    qa[1:-1] = spec.exact(x.ravel(), pp.ravel(), xcb.ravel()).reshape(uu.shape) / (
        np.broadcast_to(pre, pp.shape) * x**2)
    sb = np.empty((vk.size, p.size))
    sb[0] = sc
    vv, pp = np.meshgrid(vk[1:], p, indexing="ij")
    xcb = np.broadcast_to(xc, pp.shape)
    sb[1:] = spec.exact((xcb + vv * (xm - xcb)).ravel(), pp.ravel(),
                        xcb.ravel()).reshape(vv.shape)
    coef_q = spline_coefficients(uk, qa)
    # clamp the flight spline to the contact spline's slope at x_c: S = pre x^2 Q(x/x_c),
    # dS/dx = pre x_c (2 Q(1) + Q'(1)), dv/dx = 1/(x_max - x_c)
    h = uk[-1] - uk[-2]
    dq = (3 * coef_q[0, -1] * h + 2 * coef_q[1, -1]) * h + coef_q[2, -1]
    slope = pre * xc * (2.0 * qa[-1] + dq) * (xm - xc)
    return {
        "n_nodes": p, "u_knots": uk, "v_knots": vk, "xc_nodes": xc,
        "q_contact": qa, "s_flight": sb, "kink_slope": slope,
        "xc_cheb": to_chebyshev(xc, nu),
        "coef_contact": to_chebyshev(coef_q, nu),
        "coef_flight": to_chebyshev(
            spline_coefficients(vk, sb, slope if spec.kink_c1 else None), nu),
        "x_max": np.asarray(xm), "p_range": np.asarray([spec.p_lo, spec.p_hi]),
    }


def _build_pieces(spec: BackboneSpec) -> dict[str, np.ndarray]:
    from dataclasses import replace

    edges = np.array([spec.p_lo, *spec.p_breaks, spec.p_hi], float)
    if np.any(np.diff(edges) <= 0):
        raise ValueError(f"p_breaks {spec.p_breaks} not increasing inside [p_lo, p_hi]")
    ms = spec.m_pieces or (spec.m_cheb,) * (edges.size - 1)
    if len(ms) != edges.size - 1:
        raise ValueError(f"m_pieces {ms}: one node count per piece ({edges.size - 1})")
    parts = [_build_single(replace(spec, p_lo=float(a), p_hi=float(b), m_cheb=int(m)))
             for a, b, m in zip(edges[:-1], edges[1:], ms)]
    m_max = max(ms)
    pad = lambda a: np.pad(a, [(0, 0)] * (a.ndim - 1) + [(0, m_max - a.shape[-1])])
    out = {k: np.concatenate([d[k] for d in parts], axis=-1)
           for k in ("n_nodes", "xc_nodes", "q_contact", "s_flight", "kink_slope")}
    out.update({k: np.stack([pad(d[k]) for d in parts]) for k in _CHEB_KEYS})
    out.update({"u_knots": parts[0]["u_knots"], "v_knots": parts[0]["v_knots"],
                "x_max": np.asarray(spec.x_max), "p_range": edges[[0, -1]], "p_edges": edges})
    return out


# arrays that do not depend on q: shared by the one-coordinate tables of a q-table
_Q_SHARED = ("n_nodes", "u_knots", "v_knots", "x_max", "p_range", "p_edges", "p_cells")


def _build_two(spec: BackboneSpec) -> dict[str, np.ndarray]:
    from dataclasses import replace

    if spec.p_cells or spec.m_q < 1:
        raise ValueError("a table with a second shape coordinate needs m_q >= 1 and no "
                         "p_cells (it is read at one (p, q) for all points)")
    nu, qs = chebyshev.gauss_nodes(*spec.q_range, spec.m_q)
    parts = []
    for q in qs:
        at = lambda a, q=q: np.full(np.shape(a), q)
        parts.append(build(replace(
            spec, q_range=None, m_q=0,
            exact=lambda x, p, xc, at=at, q=q: spec.exact(x, p, xc, at(p)),
            kink=lambda p, at=at: spec.kink(p, at(p)),
            lindstedt=lambda p, at=at: spec.lindstedt(p, at(p)))))
    out = {k: v for k, v in parts[0].items() if k in _Q_SHARED}
    for k in parts[0]:
        if k not in _Q_SHARED:
            out[k] = np.stack([d[k] for d in parts], axis=-1)
            if k in _CHEB_KEYS:
                out[k] = to_chebyshev(out[k], nu)
    out["q_range"] = np.asarray(spec.q_range, float)
    out["q_nodes"] = qs
    return out


def _piece(table, p):
    """(piece index or None, local nu in [-1, 1], Chebyshev coefficient arrays)."""
    if "p_edges" not in table:
        p_lo, p_hi = (float(v) for v in table["p_range"])
        return None, (2.0 * p - (p_lo + p_hi)) / (p_hi - p_lo), table["xc_cheb"]
    edges = jnp.asarray(table["p_edges"])
    # a count of the breaks at or below p, not searchsorted: a handful of breaks, and
    # searchsorted's scan is an XLA while loop, slow on the CPU
    k = sum((p >= b).astype(jnp.int32) for b in np.asarray(table["p_edges"])[1:-1])
    lo, hi = edges[k], edges[k + 1]
    return k, (2.0 * p - (lo + hi)) / (hi - lo), jnp.asarray(table["xc_cheb"])[k]


def _cell_eval(coef, i, d, basis, piece=None):
    """S's cubic in d at cell i, the Chebyshev sums in p taken per point (basis (..., m))."""
    coef, i = jnp.asarray(coef), materialize(i)
    if piece is not None:
        c = jnp.einsum("...km,...m->k...", coef[materialize(piece), :, i, :], basis)
    else:
        c = jnp.einsum("k...m,...m->k...", coef[:, i, :], basis)
    return ((c[0] * d + c[1]) * d + c[2]) * d + c[3]


def kink_amplitude(table: dict[str, np.ndarray], p: jnp.ndarray, p_lo: float,
                   p_hi: float) -> jnp.ndarray:
    """x_c(p) from its Chebyshev interpolant (p_lo, p_hi: the range of an unpieced table)."""
    if "p_edges" not in table:
        nu = (2.0 * p - (p_lo + p_hi)) / (p_hi - p_lo)
        return chebyshev.basis(nu, table["xc_cheb"].size) @ jnp.asarray(table["xc_cheb"])
    _, nu, xc_cheb = _piece(table, jnp.asarray(p, float))
    return jnp.sum(chebyshev.basis(nu, xc_cheb.shape[-1]) * xc_cheb, axis=-1)


def within_amplitude(x: jnp.ndarray, x_max: float = X_MAX) -> jnp.ndarray:
    """True where 0 <= x <= x_max [-], the amplitudes a backbone table covers. Beyond
    x_max :func:`evaluate` holds the x_max value (the bead flies over more than twice its
    overlap), which is not the backbone there: the laws' ``domains`` use this test."""
    return (x >= 0.0) & (x <= x_max)


def evaluate(table: dict[str, np.ndarray], x: jnp.ndarray, p: jnp.ndarray, *,
             prefactor: Callable[[jnp.ndarray], jnp.ndarray] | None = None,
             q: jnp.ndarray | None = None) -> jnp.ndarray:
    """S(x, p) from ``table`` for x in [0, x_max], p in its range (callers clamp; both
    branches are evaluated on clamped coordinates so values and gradients stay finite).
    A table with a second shape coordinate takes it as ``q`` (clamped to its range too);
    p and q are then scalars (under vmap too: one (p, q) per call)."""
    p_lo, p_hi = (float(v) for v in table["p_range"])
    x_max = float(table["x_max"])
    xs = jnp.clip(x, 0.0, x_max)
    ps = jnp.clip(p, p_lo, p_hi)
    if "q_range" in table:
        if q is None:
            raise ValueError("this table has a second shape coordinate: give q")
        if jnp.ndim(ps) or jnp.ndim(q):
            # a (p, q) per point: each point read as its own scalar case (correct, but the
            # q- and p-sums are then taken per point)
            xs, ps, q = jnp.broadcast_arrays(xs, ps, jnp.asarray(q, float))
            one = lambda a, b, c: evaluate(table, a[None], b, prefactor=prefactor, q=c)[0]
            return jax.vmap(one)(xs.ravel(), ps.ravel(), q.ravel()).reshape(xs.shape)
        q_lo, q_hi = (float(v) for v in table["q_range"])
        nu_q = (2.0 * jnp.clip(q, q_lo, q_hi) - (q_lo + q_hi)) / (q_hi - q_lo)
        _, nu, _ = _piece(table, ps)
        pre = 1.0 if prefactor is None else prefactor(ps)
        # on local patches in (p, q): a step reads one (models.tables.patches_2d; a table with
        # pieces in p is refused there)
        return patches_2d.evaluate(table, xs, nu, nu_q, pre)
    if "p_cells" in table:
        # p's own shape: a (P, 1) column of per-protocol shapes is located once per row
        return p_cells.evaluate(table, xs, ps, prefactor)
    pre = 1.0 if prefactor is None else prefactor(ps)
    if jnp.ndim(ps) == 0:
        piece, nu, xc_cheb = _piece(table, ps)
        # one shape for all points (the sampler's case): the Chebyshev sums once per knot,
        # each knot's 4 coefficients contiguous (cells, 4, m), transposed as a constant (a
        # transpose after the sum is fused into the gather, which then recomputes the sum
        # per point); derivatives by hand (models.tables.one_shape)
        rows = jnp.asarray(np.swapaxes(p_cells.both_regions(table), -3, -2))
        if piece is not None:
            rows = rows[materialize(piece)]
        return one_shape.evaluate(table, rows, jnp.asarray(xc_cheb), xs, nu, pre)
    xs, ps = jnp.broadcast_arrays(xs, ps)
    piece, nu, xc_cheb = _piece(table, ps)
    basis = chebyshev.basis(nu, jnp.shape(xc_cheb)[-1])
    xc = jnp.sum(basis * jnp.asarray(xc_cheb), axis=-1)
    # one gather from the contact and flight cells side by side, not one per region: on
    # the CPU the per-point gathers are most of a table's cost
    inside, i, d = p_cells.amplitude_cell(table, xs, xc)
    y = _cell_eval(p_cells.both_regions(table), i, d, basis, piece)
    return jnp.where(inside, pre * xs**2 * y, y)
