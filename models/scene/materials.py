"""Materials, geometry and the bead's mass and weight.

Sphere (bead) on a plane (rod end): Hertz's effective quantities
    1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2,     1/R = 1/r1 + 1/r2,
with r2 -> infinity for the flat rod end, so R = r1 (Johnson, *Contact
Mechanics*, 1985, Eqs. 4.2-4.3; paper Eqs. 4-5).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
from jax.typing import ArrayLike

__all__ = [
    "G_STANDARD",
    "Material",
    "STAINLESS_STEEL",
    "effective_modulus",
    "effective_radius",
    "bead_mass",
    "bead_weight",
    "shear_modulus",
    "wave_speeds",
]

G_STANDARD = 9.80665
"""Standard gravity [m/s^2]."""


@dataclass(frozen=True)
class Material:
    """An isotropic elastic solid.

    Attributes: ``young`` E [Pa], ``poisson`` nu [-], ``density`` rho [kg/m^3],
    ``yield_strength`` Y [Pa] (only needed for the plastic-limit check).
    """

    name: str
    young: float
    poisson: float
    density: float
    yield_strength: float | None = None


STAINLESS_STEEL = Material("stainless steel (paper)", 200e9, 0.27, 7700.0, 6.12e9)
"""The paper's steel: E = 190-210 GPa (midpoint here), nu = 0.27, rho = 7700 kg/m^3,
Y = 6.12 GPa (the value that reproduces the paper's plastic-limit force)."""


def effective_modulus(
    young1: ArrayLike, poisson1: ArrayLike, young2: ArrayLike | None = None,
    poisson2: ArrayLike | None = None,
) -> jnp.ndarray:
    """E* [Pa] from 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2; body 2 defaults to body 1."""
    young2 = young1 if young2 is None else young2
    poisson2 = poisson1 if poisson2 is None else poisson2
    return 1.0 / ((1.0 - jnp.square(poisson1)) / young1 + (1.0 - jnp.square(poisson2)) / young2)


def effective_radius(r1: ArrayLike, r2: ArrayLike | None = None) -> jnp.ndarray:
    """R [m] from 1/R = 1/r1 + 1/r2; ``r2=None`` is a flat (R = r1)."""
    r1 = jnp.asarray(r1)
    if r2 is None:
        return r1
    return r1 * r2 / (r1 + r2)


def bead_mass(radius: ArrayLike, density: ArrayLike) -> jnp.ndarray:
    """m = (4/3) pi r^3 rho [kg]."""
    return 4.0 / 3.0 * jnp.pi * jnp.asarray(radius) ** 3 * density


def bead_weight(radius: ArrayLike, density: ArrayLike, g: ArrayLike = G_STANDARD) -> jnp.ndarray:
    """F0 = m g [N]."""
    return bead_mass(radius, density) * g


def shear_modulus(young: ArrayLike, poisson: ArrayLike) -> jnp.ndarray:
    """G = E / (2 (1 + nu)) [Pa]."""
    return young / (2.0 * (1.0 + poisson))


def wave_speeds(young: ArrayLike, poisson: ArrayLike, density: ArrayLike):
    """Bulk speeds (V_L, V_T) [m/s] and bar speed c0 = sqrt(E/rho) [m/s].

    V_L^2 = E (1-nu) / (rho (1+nu)(1-2nu)),  V_T^2 = E / (2 rho (1+nu)).
    """
    vl = jnp.sqrt(young * (1 - poisson) / (density * (1 + poisson) * (1 - 2 * poisson)))
    vt = jnp.sqrt(young / (2 * density * (1 + poisson)))
    c0 = jnp.sqrt(young / density)
    return vl, vt, c0
