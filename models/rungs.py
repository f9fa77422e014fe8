"""The rungs of the accuracy ladder: one definition, one spelling, everywhere.

Imports nothing heavy (no JAX), so the command line can list and check rungs before any
computation starts. :mod:`models.registry` re-exports these names.
"""

from __future__ import annotations

import difflib

__all__ = ["RUNGS", "LADDER", "FIT_RUNGS", "DEFAULT_RUNG", "check_rung"]

RUNGS: dict[str, str] = {
    "series": "small-amplitude (Lindstedt) series, leading term in x^2",
    "first_order": "the paper's first-order average of the tangent stiffness",
    "paper_eq25": "the paper's own formulas: first order, with its Eq. 25 for the "
                  "viscoelastic law (secant-slope artefact included)",
    "backbone": "exact conservative backbone (energy-integral quadrature, contact loss)",
    "harmonic_balance": "multi-harmonic balance of the forced, damped oscillator",
    "time_integration": "time integration of the swept-sine experiment",
}
"""Every rung, cheapest first, with what it computes."""

LADDER = ("series", "first_order", "backbone", "harmonic_balance", "time_integration")
"""The physical ladder, cheapest first (the scene planner picks among these)."""

FIT_RUNGS = ("first_order", "backbone", "paper_eq25")
"""Rungs the NumPyro models can be built at (fast paths or tables exist)."""

DEFAULT_RUNG = "backbone"
"""The most accurate rung NUTS affords for every built-in law: the comparison's default."""


def check_rung(rung: str, *, fit: bool = False) -> str:
    """``rung`` if it is a rung (a fit rung with ``fit``), else a ValueError naming them."""
    allowed = FIT_RUNGS if fit else tuple(RUNGS)
    if rung not in allowed:
        close = difflib.get_close_matches(str(rung).replace("-", "_"), allowed, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise ValueError(f"unknown rung '{rung}'{hint}; choose from {list(allowed)}")
    return rung
