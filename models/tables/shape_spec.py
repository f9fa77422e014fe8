"""A law's table specification: the shape coordinates its backbone table is built on.

A law whose exact backbone depends, at a given load, on one shape parameter s (or two,
s and t) carries a :class:`ShapeTable` as ``ContactLaw.physics.table``;
:mod:`beadrod.models.tables.shape_build` builds the table of every such law from it and
:mod:`beadrod.models.tables.shape_read` reads it back. ``reference_kw(s)`` (or
``reference_kw(s, t)``) gives the resolved keywords of one contact with that shape: the
table is built from the law's own force at those contacts, p = ln s.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import jax.numpy as jnp

__all__ = ["ShapeTable", "M_CHEB", "adhesive_reference_kw"]

M_CHEB = 16
"""Chebyshev nodes in p of a table without pieces (the default of :attr:`ShapeTable.m_cheb`)."""


@dataclass(frozen=True)
class ShapeTable:
    """A law's backbone table: ``reference_kw(s)`` the resolved keywords of a contact whose
    shape parameter is s = exp(p), p in [p_lo, p_hi]; ``held`` says what a value held at
    an end of that range means physically. A law whose shape has a second coordinate
    q = ln t (t in exp(q_range), ``m_q`` Chebyshev nodes) takes it as ``reference_kw(s, t)``.
    ``p_breaks``/``m_pieces``: an interpolant per piece in p; ``p_cells``: Hermite cells
    per piece (:mod:`beadrod.models.tables.hermite_cells`); ``kink_c1``: the backbone has
    a corner at the contact-loss amplitude (:mod:`beadrod.models.tables.surrogate`)."""

    reference_kw: Callable
    p_lo: float
    p_hi: float
    held: str
    m_cheb: int = M_CHEB
    p_breaks: tuple[float, ...] = ()
    m_pieces: tuple[int, ...] = ()
    p_cells: tuple[int, ...] = ()
    q_range: tuple[float, float] | None = None
    m_q: int = 0
    kink_c1: bool = False

    def kw(self, s, t=None) -> dict:
        """The reference contact's keywords at shape parameter s (and t, the second one,
        where the table has it)."""
        return self.reference_kw(s) if self.q_range is None else self.reference_kw(s, t)


def adhesive_reference_kw(r, pull_off_per_gamma_radius: float) -> dict:
    """Keywords of an adhesive contact whose load is r times its pull-off force
    Fc = c gamma R (c = ``pull_off_per_gamma_radius``: 3 pi for JKR, 4 pi for DMT): load
    1 N, R = 10 mm, E* = 1e11 Pa, unit mass (the backbone depends on r alone)."""
    radius, load = 0.01, 1.0
    return {"load": load, "radius": radius, "e_star": 1e11, "mass": 1.0,
            "gamma": load / (pull_off_per_gamma_radius * radius * jnp.asarray(r, float))}
