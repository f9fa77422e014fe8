"""The one registry of contact laws.

The CLI (``beadrod shift``, ``beadrod scene``), the comparison loop and the test
parametrisation iterate over :data:`LAWS`. Each entry binds a law's module
functions to a common calling convention: every function takes keyword
parameters from one context (``e_star`` [Pa], ``radius`` [m], ``load`` [N],
``mass`` [kg], ``n`` [-], ``gamma`` [J/m^2], ``damping_constant`` A [s],
``omega`` [rad/s]) and ignores the ones its law does not use. No formula lives
here: only dispatch.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import jax.numpy as jnp

from . import backbone, dmt, hertz, jkr, powerlaw, shift, viscoelastic

__all__ = ["ContactLaw", "LAWS", "get_law", "law_names", "SHIFT_METHODS"]

SHIFT_METHODS = ("first-order", "backbone")


@dataclass(frozen=True)
class ContactLaw:
    """A contact law's entry: what it needs and how to evaluate it."""

    name: str
    label: str
    needs: tuple[str, ...]
    reference: str
    _first_order: Callable[..., Any]
    _overlap: Callable[..., Any]
    _exponent: Callable[..., Any] | None = None  # power-law exponent: backbone rung applies
    _q: Callable[..., Any] | None = None
    variant_of: str | None = None

    @property
    def has_backbone(self) -> bool:
        return self._exponent is not None

    @property
    def predicts_q(self) -> bool:
        return self._q is not None

    def _check(self, p: dict[str, Any]) -> None:
        missing = [k for k in self.needs if p.get(k) is None]
        if missing:
            raise ValueError(f"law '{self.name}' needs parameter(s) {missing}")

    def shift(self, x: Any, *, method: str = "first-order", **p: Any) -> jnp.ndarray:
        """Delta f/f0 at x = delta_a/delta0 by ``method`` ('first-order' or 'backbone')."""
        if method not in SHIFT_METHODS:
            raise ValueError(f"unknown method {method!r}; choose from {SHIFT_METHODS}")
        if method == "backbone":
            if self._exponent is None:
                raise ValueError(f"law '{self.name}' has no backbone rung (the exact backbone "
                                 "covers F ~ delta^n laws: hertz, powerlaw, viscoelastic)")
            return backbone.backbone_shift(jnp.asarray(x, float), self._exponent(p))
        self._check(p)
        return self._first_order(jnp.asarray(x, float), p)

    def static_overlap(self, **p: Any) -> jnp.ndarray:
        """delta0 [m] under ``load``."""
        self._check(p)
        return self._overlap(p)

    def linear_q(self, **p: Any) -> jnp.ndarray:
        if self._q is None:
            raise ValueError(f"law '{self.name}' predicts no linear Q (no loss channel)")
        return self._q(p)


def _hertz_overlap(p):
    return hertz.static_overlap(p["load"], e_star=p["e_star"], radius=p["radius"])


def _jkr_kw(p):
    return {"e_star": p["e_star"], "radius": p["radius"], "gamma": p["gamma"]}


LAWS: dict[str, ContactLaw] = {
    law.name: law
    for law in (
        ContactLaw("hertz", "Hertz", ("e_star", "radius", "load"),
                   "Johnson 1985 Sec. 4.2; paper Eqs. 3, 6, 23",
                   lambda x, p: shift.first_order_hertz(x), _hertz_overlap,
                   _exponent=lambda p: hertz.EXPONENT),
        ContactLaw("powerlaw", "rough power law F = C delta^n", ("n",),
                   "paper Sec. 4.4, Eqs. 21, 26-27",
                   lambda x, p: shift.first_order_powerlaw(x, p["n"]),
                   lambda p: powerlaw.static_overlap(p["load"], coeff=p["coeff"], n=p["n"]),
                   _exponent=lambda p: p["n"]),
        ContactLaw("viscoelastic", "viscoelastic (Brilliantov / Kuwabara-Kono)",
                   ("e_star", "radius", "load"), "Brilliantov et al. 1996; paper Eqs. 8-9, 30",
                   lambda x, p: viscoelastic.shift_first_order(x), _hertz_overlap,
                   _exponent=lambda p: hertz.EXPONENT,
                   _q=lambda p: viscoelastic.linear_q(damping_constant=p["damping_constant"],
                                                      omega0=p["omega"])),
        ContactLaw("viscoelastic_paper_eq25", "viscoelastic, the paper's Eq. 25 (artefact)",
                   ("e_star", "radius", "load", "damping_constant", "omega"),
                   "paper Eq. 25 as the paper evaluated it; see models.viscoelastic",
                   lambda x, p: viscoelastic.shift_paper_eq25(
                       x, damping_constant=p["damping_constant"], omega=p["omega"]),
                   _hertz_overlap, variant_of="viscoelastic"),
        ContactLaw("jkr", "JKR adhesion", ("e_star", "radius", "load", "gamma"),
                   "Johnson, Kendall & Roberts 1971; paper Eqs. 13-19",
                   lambda x, p: jkr.shift_first_order(x, load=p["load"], **_jkr_kw(p)),
                   lambda p: jkr.static_overlap(p["load"], **_jkr_kw(p))),
        ContactLaw("dmt", "DMT adhesion", ("e_star", "radius", "load", "gamma"),
                   "Derjaguin, Muller & Toporov 1975",
                   lambda x, p: dmt.shift_first_order(x, load=p["load"], **_jkr_kw(p)),
                   lambda p: dmt.static_overlap(p["load"], **_jkr_kw(p))),
    )
}


def law_names(*, include_variants: bool = True) -> list[str]:
    return [k for k, v in LAWS.items() if include_variants or v.variant_of is None]


def get_law(name: str) -> ContactLaw:
    try:
        return LAWS[name]
    except KeyError:
        import difflib

        close = difflib.get_close_matches(name, list(LAWS), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise ValueError(f"unknown contact law '{name}'{hint}; choose from {list(LAWS)}") \
            from None
