"""Builds the backbone tables of every law that carries a table specification.

A law whose exact backbone depends, at a given load, only on one or two shape parameters
carries a :class:`~beadrod.models.tables.shape_spec.ShapeTable` (``ContactLaw.physics.table``):
in the relative coordinate q = delta/delta0 - 1 the backbone depends only on the restoring
force P'(q) = [F(delta0 (1+q)) - F0]/(K0 delta0) and the flight acceleration F0/(K0
delta0) (:mod:`beadrod.models.ladder.generic`), and for these laws both are functions of
the shape parameters alone (each law's ``TABLE`` says why, and what its held ends mean).
This module builds each table with :mod:`beadrod.models.tables.surrogate` from the generic
exact backbone of the law's own force at the specification's reference contacts, and
stores them together in ``models/tables/data/shape_tables.npz`` (keys 'NAME.*').

Outside a law's p range the value is held at the end; x beyond X_MAX = 2 is held too.
Fits never use a held value: the laws' domains (:func:`beadrod.models.tables.shape_read.
in_table`) give such points zero likelihood, or the law carries its table past p_hi as it
approaches Hertz's backbone (its ``HERTZ_DECAY``). The laws' backbone rungs read the tables
through :mod:`beadrod.models.tables.shape_read`, which imports no law: the dependency runs
one way. Errors against the generic exact backbone are tested per law
(tests/test_shape_tables.py).

Regenerate (deterministic; tens of minutes per law)::

    python -m beadrod.models.tables.shape_build --rebuild [--law NAME]
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.registry import get_law, laws
from beadrod.models.tables import surrogate
from beadrod.models.tables.rebuild import rebuild_cli
from beadrod.models.tables.shape_read import TABLE_PATH, X_MAX, backbone_fast, load_table
from beadrod.models.tables.shape_spec import ShapeTable

__all__ = ["X_MAX", "TABLE_PATH", "tabulated", "backbone_fast", "exact_backbone",
           "load_table", "build_table", "spec"]

# table grid and the orbit rule used to build it: 24 Gauss nodes are spectrally accurate on
# the contact arc (the flight arc's graded rule is fixed); the tests measure the table
# against the 48-node exact backbone
_N_KNOTS, _BUILD_NODES = 48, 24
_EXACT: dict[tuple[str, int], object] = {}


def tabulated() -> dict[str, ShapeTable]:
    """Law name -> table specification (``ContactLaw.physics.table``) of every registered law that
    carries one, in registry order."""
    return {law.name: law.physics.table for law in laws() if law.physics.table is not None}


def _law(name: str):
    law = get_law(name)
    if law.physics.table is None:
        raise ValueError(f"law '{name}' has no table specification; tabulated laws: "
                         f"{list(tabulated())}")
    return law


def exact_backbone(name: str, x: ArrayLike, s: ArrayLike, nodes: int = 48,
                   t: ArrayLike = 1.0) -> jnp.ndarray:
    """Exact backbone Delta f/f0 of law ``name`` at x and shape parameter s (and t, the
    second one, where the law has it): the generic quadrature of its restoring force."""
    from beadrod.models.ladder.generic import backbone_shift

    if (name, nodes) not in _EXACT:
        law = _law(name)
        tab = law.physics.table

        def one(xi, si, ti):
            kw = tab.kw(si, ti)
            return backbone_shift(law, xi, delta0=law.overlap(**kw), nodes=nodes, **kw)

        _EXACT[(name, nodes)] = jax.jit(jax.vmap(one))
    x, s, t = jnp.broadcast_arrays(*(jnp.asarray(v, float) for v in (x, s, t)))
    return _EXACT[(name, nodes)](x.ravel(), s.ravel(), t.ravel()).reshape(x.shape)


def spec(name: str) -> surrogate.BackboneSpec:
    """The surrogate specification of law ``name`` (p = ln s)."""
    from beadrod.models.ladder.generic import contact_loss_onset, lindstedt_coefficient

    tab = _law(name).physics.table

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


def build_table(names: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
    """The tables of ``names`` (keys prefixed 'NAME.'), merged into the stored ones."""
    names = tuple(tabulated()) if names is None else names
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
                       build=build_table, path=TABLE_PATH, parts=tuple(tabulated()))


if __name__ == "__main__":
    raise SystemExit(_main())
