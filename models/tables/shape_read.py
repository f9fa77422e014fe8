"""Fast backbones of the one-shape-parameter laws (JKR, DMT, Greenwood-Williamson), read
from their stored tables.

The evaluation half of :mod:`models.tables.shape_build`: the laws' backbone rungs call
:func:`backbone_fast`, and :mod:`models.tables.shape_build` builds the tables from the laws'
forces (it imports the laws), so the dependency runs one way, law -> this module <-
builder. Nothing here needs a law object: each table carries its own shape range
(``p_range``, p = ln s) and amplitude range (``x_max``), written by
:func:`models.tables.surrogate.build` from the builder's each law's ``TABLE``.

Shape parameters s (what each law passes): JKR r = F0/Fc, Fc = 3 pi gamma R; DMT
r = F0/Fc, Fc = 4 pi gamma R; Greenwood-Williamson D0' = delta0'/sigma (overlap counted
from the contact edge -6 sigma). Outside a table's range the value is held at its end,
and the held value is not the law's backbone: :func:`in_table` says so (the laws'
``domains``; a command computes those points by the generic quadrature, a sampler counts
none of them). Above p_hi the laws tend to Hertz's backbone, but slowly: at the end the
tables still stand 2.0e-4 (JKR, r = 1000), 3.0e-4 (DMT) and 3.2e-4 (Greenwood-Williamson,
D0' = 1e4) from it near x = 2, ten times their stated errors. A law that states how it
approaches Hertz's backbone (s^-k: ``decay``, measured with the generic backbone in the
law's module) has its departure at the end carried on as (s_hi/s)^k, and its domain has
no upper end (all four tabulated laws do); a law that does not has its domain end at p_hi
(the value held there is not the law's). For the
paper's scene the end is gamma = 0.0016-0.0021 J/m^2 (DMT to JKR, 11.6-12.2 prior sd below
the median) and a roughness factor 2.1e-4 (12 sd).
"""

from __future__ import annotations

import pathlib

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.tables import surrogate
from beadrod.models.tables.powerlaw_backbone import backbone_shift_fast

__all__ = ["X_MAX", "TABLE_PATH", "backbone_fast", "in_table", "load_table", "shape_range"]

X_MAX = surrogate.X_MAX
"""Largest tabulated amplitude x = delta_a/delta0 [-]; beyond it the value is held."""
TABLE_PATH = pathlib.Path(__file__).with_name("data") / "shape_tables.npz"

_TABLES: dict[str, dict[str, np.ndarray]] = {}


def load_table(name: str) -> dict[str, np.ndarray]:
    """The stored table of law ``name`` (numpy arrays, loaded once; keys 'NAME.*' in the
    file)."""
    if not _TABLES:
        with np.load(TABLE_PATH) as f:
            for key in f.files:
                law, k = key.split(".", 1)
                _TABLES.setdefault(law, {})[k] = f[key]
    return _TABLES[name]


def shape_range(name: str) -> tuple[float, float]:
    """(p_lo, p_hi) of law ``name``'s table, p = ln s [-]: the range it was built on."""
    lo, hi = load_table(name)["p_range"]
    return float(lo), float(hi)


def _log(s):
    return jnp.log(jnp.maximum(jnp.asarray(s, float), 1e-300))


def backbone_fast(name: str, x: ArrayLike, s: ArrayLike,
                  t: ArrayLike | None = None, *, decay: float | None = None) -> jnp.ndarray:
    """Tabulated backbone Delta f/f0 [-] of law ``name`` at x = delta_a/delta0 (delta0 the
    law's overlap) and shape parameter s (and t, the second one, for a table that has it:
    Maugis-Dugdale's lam; s and t scalars then); x clipped to [0, X_MAX], ln s and ln t
    to the table's ranges (values held at the ends: each law's ``TABLE``).

    ``decay``: k > 0 for a law whose backbone tends to Hertz's as s -> inf like s^-k.
    Above p_hi the table's departure from Hertz's backbone at its end then decays as
    (s_hi/s)^k instead of being held (the module doc: the law's own approach, measured),
    and :func:`in_table` has no upper end for it. Differentiable, NaN-free."""
    p_lo, p_hi = shape_range(name)
    ln_s = _log(s)
    q = None if t is None else _log(t)
    x = jnp.asarray(x, float)
    value = surrogate.evaluate(load_table(name), x, jnp.clip(ln_s, p_lo, p_hi), q=q)
    if decay is None:
        return value
    over = jnp.maximum(ln_s - p_hi, 0.0)

    def carried(v):
        hertz = backbone_shift_fast(jnp.clip(x, 0.0, X_MAX), 1.5)
        return hertz + (v - hertz) * jnp.exp(-decay * over)

    # Hertz's table only where some s lies past the end: read at every sweep point of
    # every step it would cost a sampler as much as the law's own table; under vmap
    # both branches run
    return jax.lax.cond(jnp.any(over > 0.0), carried, lambda v: v, value)


def in_table(name: str, x: ArrayLike, s: ArrayLike, t: ArrayLike | None = None, *,
             decay: float | None = None) -> jnp.ndarray:
    """True where law ``name``'s table gives its backbone: 0 <= x <= X_MAX and ln s in
    [p_lo, p_hi] (beyond either end the held value is not the law's, the module doc;
    ln s >= p_lo only, where :func:`backbone_fast` carries the law past p_hi with
    ``decay``); for a table with a second coordinate, also ln t inside its range."""
    p_lo, p_hi = shape_range(name)
    x = jnp.asarray(x, float)
    p = _log(s)
    ok = surrogate.within_amplitude(x, X_MAX) & (p >= p_lo - 1e-12)
    if decay is None:
        ok = ok & (p <= p_hi + 1e-12)
    table = load_table(name)
    if "q_range" in table:
        q_lo, q_hi = (float(v) for v in table["q_range"])
        q = _log(t)
        ok = ok & (q >= q_lo - 1e-12) & (q <= q_hi + 1e-12)
    return ok
