"""Adhesion map and the plastic-limit check (paper Secs. 4.2-4.3, Eq. 15).

Muller parameter (paper Eq. 15, as the paper evaluates it: with the surface energy gamma,
not the work of adhesion w = 2 gamma; gamma = 0.7 J/m^2, z0 = 0.4 nm and E = 210 GPa give
the paper's mu = 57, w would give 90)::

    mu = (32 / (3 pi z0)) (gamma^2 R / E*^2)^(1/3),   Tabor lambda = 1.16 mu (as the paper).

Load-to-adhesion ratio: the adhesion force scale is pi w R = 2 pi gamma R (the
normalisation of Johnson & Greenwood's adhesion map, J. Colloid Interface Sci. 192, 326
(1997)); the paper quotes its inverse, F0/(2 pi gamma R) = 4.5.

Regimes (paper Sec. 4.3 after Johnson & Greenwood 1997): Hertz when adhesion/load < 0.05;
otherwise DMT for mu < 1, JKR for mu > 5, Maugis-Dugdale between.

Plastic limit (onset of yield, paper Sec. 4.2 and its ref. [2])::

    Fl = pi^3 (1.6 Y)^3 R^2 / (24 E*^2)        ("paper")
    Fl = pi^3 (1.6 Y)^3 R^2 / (6 E*^2)         ("johnson": K. L. Johnson, Contact
                                                Mechanics, Sec. 6.2, p0 = 1.6 Y)

The paper's "1.63 pi3 Y3" is the extraction of 1.6^3 pi^3 Y^3 (superscript lost): with
1.6^3 and Y = 6.12 GPa the paper's ~6.5e3 N is reproduced at E = 200 GPa; a literal 1.63
gives 2.4-2.9e3 N. The paper's 1/24 equals Johnson's 1/6 with R = r/2 (two equal
spheres); for a sphere on a flat (R = r) Johnson's onset is 4 times larger.
"""

from __future__ import annotations

from typing import Literal

import jax.numpy as jnp
from jax.typing import ArrayLike

__all__ = ["adhesive_alternatives",
    "Z0_DEFAULT",
    "muller_parameter",
    "tabor_parameter",
    "adhesion_force_scale",
    "adhesion_to_load_ratio",
    "adhesion_regime",
    "plastic_limit_force",
    "dynamic_force",
]

Z0_DEFAULT = 0.4e-9
"""Equilibrium separation z0 [m] (paper, its ref. [36])."""

HERTZ_RATIO = 0.05
DMT_MU = 1.0
JKR_MU = 5.0


def muller_parameter(
    *, gamma: ArrayLike, radius: ArrayLike, e_star: ArrayLike, z0: ArrayLike = Z0_DEFAULT
) -> jnp.ndarray:
    """mu = (32/(3 pi z0)) (gamma^2 R/E*^2)^(1/3) [-] (paper Eq. 15); gamma [J/m^2]."""
    return 32.0 / (3.0 * jnp.pi * z0) * jnp.cbrt(jnp.square(gamma) * radius / jnp.square(e_star))


def tabor_parameter(
    *, gamma: ArrayLike, radius: ArrayLike, e_star: ArrayLike, z0: ArrayLike = Z0_DEFAULT
) -> jnp.ndarray:
    """lambda = 1.16 mu [-] (the paper's relation)."""
    return 1.16 * muller_parameter(gamma=gamma, radius=radius, e_star=e_star, z0=z0)


def adhesion_force_scale(*, gamma: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """Fa = pi w R = 2 pi gamma R [N], the adhesion-map force scale."""
    return 2.0 * jnp.pi * gamma * radius


def adhesion_to_load_ratio(
    load: ArrayLike, *, gamma: ArrayLike, radius: ArrayLike
) -> jnp.ndarray:
    """Fa/F = 2 pi gamma R / F [-] (the paper's 4.5 is F0/(2 pi gamma R), the inverse)."""
    return adhesion_force_scale(gamma=gamma, radius=radius) / load


def adhesion_regime(
    load: float, *, gamma: float, radius: float, e_star: float, z0: float = Z0_DEFAULT
) -> dict:
    """Which contact law the adhesion map selects, and why (plain floats; not traced).

    Returns dict(law="Hertz"|"DMT"|"Maugis-Dugdale"|"JKR", reason=str, mu=float,
    ratio=float) with ratio = adhesion/load.
    """
    mu = float(muller_parameter(gamma=gamma, radius=radius, e_star=e_star, z0=z0))
    ratio = float(adhesion_to_load_ratio(load, gamma=gamma, radius=radius))
    if ratio < HERTZ_RATIO:
        law = "Hertz"
        reason = (f"adhesion force 2 pi gamma R is {ratio:.3g} of the load (< {HERTZ_RATIO}): "
                  "adhesion negligible, Hertz applies")
    elif mu < DMT_MU:
        law = "DMT"
        reason = (f"adhesion is {ratio:.3g} of the load (>= {HERTZ_RATIO}) and Muller mu = "
                  f"{mu:.3g} < {DMT_MU}: stiff solids, long-range adhesion, DMT applies")
    elif mu > JKR_MU:
        law = "JKR"
        reason = (f"adhesion is {ratio:.3g} of the load (>= {HERTZ_RATIO}) and Muller mu = "
                  f"{mu:.3g} > {JKR_MU}: compliant solids, short-range adhesion, JKR applies")
    else:
        law = "Maugis-Dugdale"
        reason = (f"adhesion is {ratio:.3g} of the load (>= {HERTZ_RATIO}) and Muller mu = "
                  f"{mu:.3g} is between {DMT_MU} and {JKR_MU}: transition, Maugis-Dugdale")
    return {"law": law, "reason": reason, "mu": mu, "ratio": ratio}


def adhesive_alternatives(regime: dict) -> tuple[str, ...]:
    """The adhesive contacts whose difference from Hertz bounds leaving adhesion out of a
    scene in ``regime`` (:func:`adhesion_regime`): the selected one; for Maugis-Dugdale
    both ends of its range, JKR and DMT (Johnson & Greenwood 1997); for Hertz the end the
    Muller parameter is nearer (JKR for mu >= 1, else DMT)."""
    law = regime["law"]
    if law == "Hertz":
        return ("JKR" if regime["mu"] >= 1.0 else "DMT",)
    if law == "Maugis-Dugdale":
        return ("JKR", "DMT")
    return (law,)


def plastic_limit_force(
    *,
    yield_strength: ArrayLike,
    radius: ArrayLike,
    e_star: ArrayLike,
    convention: Literal["paper", "johnson"] = "paper",
) -> jnp.ndarray:
    """Load Fl [N] at which yield starts: pi^3 (1.6 Y)^3 R^2/(d E*^2), d = 24 ("paper") or
    6 ("johnson", sphere on flat with R the effective radius). See module docstring."""
    denominator = {"paper": 24.0, "johnson": 6.0}[convention]
    return jnp.pi**3 * (1.6 * yield_strength) ** 3 * jnp.square(radius) / (
        denominator * jnp.square(e_star)
    )


def dynamic_force(mass: ArrayLike, omega: ArrayLike, amplitude: ArrayLike) -> jnp.ndarray:
    """Fd = m omega^2 delta [N]: inertial force amplitude of mass m [kg] moving with amplitude
    delta [m] at omega [rad/s] (paper: ~0.3 N at 3 kHz with the Hertz delta0)."""
    return mass * jnp.square(omega) * amplitude
