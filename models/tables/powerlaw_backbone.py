"""Tabulated exact backbone (ladder rung 3) for F ~ delta^n, fast enough for NUTS.

:func:`backbone_shift_fast` reproduces :func:`models.ladder.backbone.backbone_shift` (the exact
conservative backbone Delta f/f0 at first-harmonic amplitude x = delta_a/delta0, contact
loss included) on the domain n in [1, 3], x in [0, X_MAX = 2], from a table computed once
by the exact function and stored in ``models/tables/data/backbone_table.npz``.

Structure of the function (measured, see the tests):

* Contact loss starts at qmax_c(n) = (n+1)^(1/n) - 1 (P(qmax) = P(-1)), i.e. at the
  first-harmonic amplitude x_c(n) = a1(qmax_c) (x_c = 1 for n = 1, 0.9213 for Hertz,
  0.7753 for n = 3). At x_c the backbone is C1 but not C2: on both sides it carries a
  term ~ |x - x_c|^(n + 1/2) (the y^(n+1) term of the potential at the contact edge),
  so the second derivative is infinite there for n < 3/2 and jumps for larger n. For
  n = 1 the left side is identically 0 (linear spring) and the right side is
  ~ (x - 1)^(3/2). The domain is therefore split at x_c(n), with kink-aligned
  coordinates u = x/x_c(n) (contact) and v = (x - x_c)/(X_MAX - x_c) (flight).
* Below x_c, S = (n - 1) x^2 Q(u, n) with Q smooth and Q(0, n) = -(2n+1)/48, the
  Lindstedt coefficient (n-1)(n-2)/16 - 5(n-1)^2/48 = -(n-1)(2n+1)/48 divided by n - 1
  (:func:`models.ladder.backbone.lindstedt_shift`): relative accuracy at small x, exact 0 at
  x = 0 and for n = 1.

Method: in each region a cubic spline (C2) in u (resp. v) on 64 knots graded
quadratically towards the kink (u_i = 1 - (1 - i/63)^2, v_i = (i/63)^2), tensor product
with a degree-23 Chebyshev interpolant in n on the 24 Chebyshev-Gauss nodes of [1, 3]
(no node at n = 1, where Q = S/((n-1) x^2) is 0/0); x_c(n) is a Chebyshev interpolant on
the same nodes (error 7e-14). The contact spline is not-a-knot; the flight spline is
clamped at v = 0 to the contact spline's slope there, so the surrogate is C1 across
x_c like the exact backbone (C2 elsewhere). Samples: the exact backbone with 48 Gauss
nodes, but 128 within 0.05 of x_c (:func:`exact_shift`, so that the stored table is
regenerated bit for bit), and the exact orbit at qmax_c (1 - 1e-12) for the kink values;
Q(0, n) is the Lindstedt coefficient.
Table: 64 x 24 samples per region, 0.13 MB.

Measured (``python -m pytest -m slow tests/test_backbone_table.py``, 2000 random points
plus x_c +- 3e-6..3e-2 for 12 values of n; reference: exact backbone, 128 nodes within
0.05 of x_c): max |Delta f/f0 error| 6.8e-8, next to the kink for n -> 1 (the
|x - x_c|^(3/2) term in the first cubic piece; the n = 1 closed form confirms it);
8e-9 farther than 0.01 from x_c. Relative error at small x: 3e-7 at x = 1e-3 (the
next-order Lindstedt term is tracked). Gradients against central differences of the
exact backbone (60 random points away from x_c): |d/dx error| <= 1.7e-7, |d/dn error|
<= 1.5e-8 (relative <= 4e-6).

Outside the domain (x < 0, x > X_MAX, n outside [1 - 1e-9, 3 + 1e-9]) the result is NaN,
never an extrapolation. Regenerate the table (deterministic, bit-identical; most of the
time goes to the exact backbone)::

    python -m beadrod.models.tables.powerlaw_backbone --rebuild
"""

from __future__ import annotations

import pathlib

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.tables import surrogate
from beadrod.models.tables.rebuild import rebuild_cli

__all__ = [
    "X_MAX",
    "N_MIN",
    "N_MAX",
    "TABLE_PATH",
    "backbone_shift_fast",
    "backbone_shift_clipped",
    "contact_loss_amplitude",
    "load_table",
    "build_table",
    "exact_shift",
    "SPEC",
]

X_MAX = surrogate.X_MAX
N_MIN, N_MAX = 1.0, 3.0
_N_TOL = 1e-9
TABLE_PATH = pathlib.Path(__file__).with_name("data") / "backbone_table.npz"

_M_CHEB = 24        # Chebyshev nodes in n
_N_KNOTS = 64       # spline knots per region
_NEAR_KINK = 0.05   # flight-side samples this close to x_c use the fine quadrature
_FINE_NODES = 128

_TABLE: dict[str, np.ndarray] | None = None


# --------------------------------------------------------------------------- build
def _kink(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(x_c, S_c) at the onset of contact loss, from the exact orbit just below qmax_c."""
    from beadrod.models.ladder.backbone import powerlaw_orbit

    qc = (n + 1.0) ** (1.0 / n) - 1.0
    om, a1, _ = jax.vmap(powerlaw_orbit)(jnp.asarray(qc * (1.0 - 1e-12)), jnp.asarray(n))
    return np.asarray(a1), np.asarray(om) - 1.0


def exact_shift(x: np.ndarray, n: np.ndarray, xc: np.ndarray) -> np.ndarray:
    """Exact backbone, with 128 Gauss nodes within _NEAR_KINK of x_c and 48 elsewhere."""
    from beadrod.models.ladder.backbone import backbone_shift

    near = np.abs(x - xc) < _NEAR_KINK
    out = np.empty_like(x)
    for sel, nodes in ((near, _FINE_NODES), (~near, 48)):
        if sel.any():
            out[sel] = np.asarray(backbone_shift(jnp.asarray(x[sel]), jnp.asarray(n[sel]),
                                                 nodes=nodes))
    return out


def _lindstedt_q0(n: np.ndarray) -> np.ndarray:
    from beadrod.models.ladder.backbone import lindstedt_shift

    return np.asarray(lindstedt_shift(1.0, n))


SPEC = surrogate.BackboneSpec(
    p_lo=N_MIN, p_hi=N_MAX, exact=lambda x, n, xc: exact_shift(x, n, xc), kink=_kink,
    lindstedt=_lindstedt_q0, prefactor=lambda n: n - 1.0, x_max=X_MAX, m_cheb=_M_CHEB,
    n_knots=_N_KNOTS)
"""The power law's surrogate: p = n in [1, 3], S = (n - 1) x^2 Q below x_c."""


def build_table() -> dict[str, np.ndarray]:
    """Evaluate the exact backbone on the grid and fit the splines (deterministic)."""
    return surrogate.build(SPEC)


def load_table() -> dict[str, np.ndarray]:
    """The stored table as numpy arrays (loaded once; no JAX arrays at import time)."""
    global _TABLE
    if _TABLE is None:
        with np.load(TABLE_PATH) as f:
            _TABLE = {k: f[k] for k in f.files}
        _TABLE.setdefault("p_range", np.asarray([N_MIN, N_MAX]))  # the stored file has none
    return _TABLE


@jax.jit
def contact_loss_amplitude(n: ArrayLike) -> jnp.ndarray:
    """x_c(n): first-harmonic amplitude at which the orbit first leaves contact [-].

    Chebyshev interpolant of a1(qmax_c) with qmax_c = (n+1)^(1/n) - 1, n in [1, 3].
    """
    return surrogate.kink_amplitude(load_table(), jnp.asarray(n, dtype=float), N_MIN, N_MAX)


@jax.jit
def backbone_shift_fast(x: ArrayLike, n: ArrayLike = 1.5) -> jnp.ndarray:
    """Tabulated exact backbone Delta f/f0 [-] at first-harmonic amplitude x = delta_a/delta0.

    Same semantics as :func:`models.ladder.backbone.backbone_shift` (F ~ delta^n, weight
    preload, contact loss; broadcasting x and n; 0 at x = 0) on 0 <= x <= X_MAX = 2 and
    1 <= n <= 3 (tolerance 1e-9); NaN outside. Absolute error <= 1e-6 (measured 6.8e-8
    worst, at the kink for n -> 1; ~1e-8 elsewhere), relative error at small x < 1e-6
    for x <= 1e-3. Differentiable in x and n: C2 in x except at the contact-loss
    amplitude x_c(n) (:func:`contact_loss_amplitude`), where it is C1, like the exact
    backbone.
    """
    tab = load_table()
    x, n = jnp.asarray(x, dtype=float), jnp.asarray(n, dtype=float)
    if n.ndim > 0:  # a scalar n stays scalar: see surrogate._cell_eval
        x, n = jnp.broadcast_arrays(x, n)
    inside = surrogate.within_amplitude(x, X_MAX) & (n >= N_MIN - _N_TOL) & (n <= N_MAX + _N_TOL)
    s = surrogate.evaluate(tab, x, n, prefactor=lambda ns: ns - 1.0)
    return jnp.where(inside, s, jnp.nan)


def backbone_shift_clipped(x: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """:func:`backbone_shift_fast` with x clipped to [0, X_MAX] and n to [N_MIN, N_MAX].

    What the samplers use: past x = 2 (delta_a > 2 delta0, only for absurd parameters) the
    curve is held at its x = 2 value and the misfit is left to the likelihood, so no NaN
    reaches NUTS; n outside [1, 3] is refused by the priors, the clip only guards rounding.
    """
    return backbone_shift_fast(jnp.clip(jnp.asarray(x, float), 0.0, X_MAX),
                               jnp.clip(jnp.asarray(n, float), N_MIN, N_MAX))


def _main(argv: list[str] | None = None) -> int:
    return rebuild_cli(argv, prog="python -m beadrod.models.tables.powerlaw_backbone",
                       description="Tabulated exact backbone for F ~ delta^n.",
                       build=build_table, path=TABLE_PATH)


if __name__ == "__main__":
    raise SystemExit(_main())
