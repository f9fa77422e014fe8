"""Fast backbones of the one-shape-parameter laws (JKR, DMT, Greenwood-Williamson), read
from their stored tables.

The evaluation half of :mod:`models.shape_tables`: the laws' backbone rungs call
:func:`backbone_fast`, and :mod:`models.shape_tables` builds the tables from the laws'
forces (it imports the laws), so the dependency runs one way, law -> this module <-
builder. Nothing here needs a law object: each table carries its own shape range
(``p_range``, p = ln s) and amplitude range (``x_max``), written by
:func:`models.surrogate.build` from the builder's :data:`models.shape_tables.TABLES`.

Shape parameters s (what each law passes): JKR r = F0/Fc, Fc = 3 pi gamma R; DMT
r = F0/Fc, Fc = 4 pi gamma R; Greenwood-Williamson D0' = delta0'/sigma (overlap counted
from the contact edge -6 sigma). Outside a table's range the value is held at its end.
Above p_hi that is each law's Hertz limit (adhesion or roughness below 1e-3 of the load
or the overlap), within the table's error; below p_lo and beyond X_MAX it is not the
law's backbone, and :func:`in_table` says so (the laws' ``domains``).
"""

from __future__ import annotations

import pathlib

import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from . import surrogate

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
                  t: ArrayLike | None = None) -> jnp.ndarray:
    """Tabulated backbone Delta f/f0 [-] of law ``name`` at x = delta_a/delta0 (delta0 the
    law's overlap) and shape parameter s (and t, the second one, for a table that has it:
    Maugis-Dugdale's lam; s and t scalars then); x clipped to [0, X_MAX], ln s and ln t
    to the table's ranges (values held at the ends: :data:`models.shape_tables.TABLES`).
    Differentiable, NaN-free."""
    p_lo, p_hi = shape_range(name)
    p = jnp.clip(_log(s), p_lo, p_hi)
    q = None if t is None else _log(t)
    return surrogate.evaluate(load_table(name), jnp.asarray(x, float), p, q=q)


def in_table(name: str, x: ArrayLike, s: ArrayLike, t: ArrayLike | None = None) -> jnp.ndarray:
    """True where law ``name``'s table gives its backbone: 0 <= x <= X_MAX and
    ln s >= p_lo (above p_hi the held value is the Hertz limit, see the module doc); for a
    table with a second coordinate, also ln t inside its range (no limit is held there)."""
    p_lo, _ = shape_range(name)
    x = jnp.asarray(x, float)
    ok = surrogate.within_amplitude(x, X_MAX) & (_log(s) >= p_lo - 1e-12)
    table = load_table(name)
    if "q_range" in table:
        q_lo, q_hi = (float(v) for v in table["q_range"])
        q = _log(t)
        ok = ok & (q >= q_lo - 1e-12) & (q <= q_hi + 1e-12)
    return ok
