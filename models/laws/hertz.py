"""Hertz contact of a sphere on a plane.

    F = (4/3) E* R^(1/2) delta^(3/2)                      (paper Eq. 3)
    K_N = dF/d delta = 2 E* (R delta)^(1/2)               (paper Eq. 6)
    delta0 = (3 F0 / (4 E* R^(1/2)))^(2/3),  K0 = (3/2) F0 / delta0,
    f0 = (1/2 pi) (K0 / m)^(1/2)                          (paper Eq. 7)

Reference: K. L. Johnson, *Contact Mechanics* (CUP 1985), Sec. 4.2. Forces
are unilateral: F = 0 and K_N = 0 for delta <= 0 (contact lost).
"""

from __future__ import annotations

import jax.numpy as jnp
from jax.typing import ArrayLike

from beadrod.models.safe_math import safe_pow

__all__ = [
    "EXPONENT",
    "force",
    "stiffness",
    "static_overlap",
    "linear_stiffness",
    "linear_frequency",
    "overlap_from_frequency",
    "frequency_from_overlap",
    "stiffness_constant",
    "mechanics",
]

EXPONENT = 1.5
"""The Hertz exponent n in F proportional to delta^n."""


def stiffness_constant(*, e_star: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """k_n = (4/3) E* R^(1/2) [N/m^(3/2)], the Kuwabara-Kono elastic constant."""
    return 4.0 / 3.0 * e_star * jnp.sqrt(radius)


def force(delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """F(delta) = (4/3) E* R^(1/2) delta^(3/2) [N]; 0 for delta <= 0."""
    return stiffness_constant(e_star=e_star, radius=radius) * safe_pow(delta, 1.5)


def stiffness(delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """Tangent stiffness K_N = 2 E* (R delta)^(1/2) [N/m]; 0 for delta <= 0."""
    return 2.0 * e_star * jnp.sqrt(radius) * safe_pow(delta, 0.5)


def static_overlap(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """delta0 = (3 F0 / (4 E* R^(1/2)))^(2/3) [m] under a compressive load F0 [N]."""
    return safe_pow(load / stiffness_constant(e_star=e_star, radius=radius), 2.0 / 3.0)


def linear_stiffness(load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """K0 = 2 E* (R delta0)^(1/2) = (3/2) F0 / delta0 [N/m]."""
    return stiffness(static_overlap(load, e_star=e_star, radius=radius), e_star=e_star,
                     radius=radius)


def linear_frequency(
    load: ArrayLike, mass: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike
) -> jnp.ndarray:
    """f0 = (1/2 pi) (K0/m)^(1/2) [Hz] of the bead (mass m [kg]) on the contact."""
    k0 = linear_stiffness(load, e_star=e_star, radius=radius)
    return jnp.sqrt(k0 / mass) / (2.0 * jnp.pi)


def overlap_from_frequency(f0: ArrayLike, load: ArrayLike, mass: ArrayLike) -> jnp.ndarray:
    """delta0 [m] that a measured linear resonance f0 [Hz] implies under load F0 [N].

    K0 = (3/2) F0/delta0 = m (2 pi f0)^2, so delta0 = 3 F0 / (2 m (2 pi f0)^2);
    for a weight preload (F0 = m g) this is 3 g / (2 omega0^2), independent of E*.
    """
    return 1.5 * load / (mass * jnp.square(2.0 * jnp.pi * f0))


def frequency_from_overlap(delta0: ArrayLike, load: ArrayLike, mass: ArrayLike) -> jnp.ndarray:
    """f0 = (3 F0 / (2 m delta0))^(1/2) / (2 pi) [Hz]: the inverse of
    :func:`overlap_from_frequency` (delta0 [m], F0 [N], m [kg])."""
    return jnp.sqrt(1.5 * load / (mass * delta0)) / (2.0 * jnp.pi)


def mechanics() -> dict:
    """The Hertz contact's entries of :class:`models.law.Physics` (force, static overlap,
    and the overlap-frequency map under the weight), for every law whose elastic contact
    is Hertz's (Hertz, the viscoelastic laws, Hertz with hysteresis)."""
    return {
        "force": lambda delta, *, e_star, radius, **_: force(delta, e_star=e_star,
                                                             radius=radius),
        "static_overlap": lambda *, load, e_star, radius, **_: static_overlap(
            load, e_star=e_star, radius=radius),
        "overlap_from_frequency": lambda f0, *, load, mass, **_: overlap_from_frequency(
            f0, load, mass),
        "frequency_from_overlap": lambda d, *, load, mass, **_: frequency_from_overlap(
            d, load, mass),
    }


def _law():
    from beadrod.models.ladder.first_order import first_order_hertz
    from beadrod.models.law import YOUNG, ContactLaw, Physics, Presentation
    from beadrod.models.rungs import LADDER
    from beadrod.models.tables.powerlaw_backbone import backbone_shift_clipped
    from beadrod.models.tables.surrogate import within_amplitude

    return ContactLaw(
        name="hertz",
        params=(YOUNG,),
        physics=Physics(
            **mechanics(),
            # the paper analysed this law at first order: its 'paper_eq25' rung is first order
            rungs=(*LADDER, "paper_eq25"),
            shifts={"first_order": lambda x, **_: first_order_hertz(x),
                    "paper_eq25": lambda x, **_: first_order_hertz(x),
                    "backbone": lambda x, **_: backbone_shift_clipped(x, EXPONENT)},
            # the table holds its x = 2 value beyond; the inference counts no point there
            domains={"backbone": lambda x, **_: within_amplitude(x)},
        ),
        presentation=Presentation(
            label="Hertz", color="#0072B2",
            reference="Johnson 1985 Sec. 4.2; paper Eqs. 3, 6, 23",
            description="elastic sphere on a plane, F = (4/3) E* R^(1/2) delta^(3/2)",
        ),
    )


LAW = _law()
"""The Hertz contact law (:class:`models.law.ContactLaw`)."""
__all__ += ["LAW"]
