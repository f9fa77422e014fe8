"""Rough-surface power law F = C delta^n (paper Sec. 4.4, Eq. 21).

For a self-affine rough surface of Hurst exponent H (0 < H <= 2) the
load-overlap exponent is n = (1 + H)/H; n = 3/2 recovers Hertz (H = 2) and a
soft oxide shell gives n = 2 (H = 1). Under a preload F0,
    delta0 = (F0/C)^(1/n),   K0 = n C delta0^(n-1) = n F0/delta0,
so with a weight preload (F0 = m g) omega0^2 = n g / delta0 whatever C is:
the prefactor C is not identifiable from resonance data and the law is best
parameterised by (delta0, n).
"""

from __future__ import annotations

import jax.numpy as jnp
from jax.typing import ArrayLike

from beadrod.models.safe_math import safe_pow

__all__ = [
    "exponent_from_hurst",
    "hurst_from_exponent",
    "force",
    "stiffness",
    "static_overlap",
    "coefficient_from_overlap",
    "linear_stiffness",
    "linear_frequency",
    "overlap_from_frequency",
    "frequency_from_overlap",
]


def exponent_from_hurst(hurst: ArrayLike) -> jnp.ndarray:
    """n = (1 + H)/H [-]."""
    return (1.0 + hurst) / hurst


def hurst_from_exponent(n: ArrayLike) -> jnp.ndarray:
    """H = 1/(n - 1) [-], the inverse of :func:`exponent_from_hurst`."""
    return 1.0 / (n - 1.0)


def force(delta: ArrayLike, *, coeff: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """F = C delta^n [N]; 0 for delta <= 0. ``coeff`` C in [N/m^n]."""
    return coeff * safe_pow(delta, n)


def stiffness(delta: ArrayLike, *, coeff: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """K_N = n C delta^(n-1) [N/m]; 0 for delta <= 0."""
    return n * coeff * safe_pow(delta, n - 1.0)


def static_overlap(load: ArrayLike, *, coeff: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """delta0 = (F0/C)^(1/n) [m]."""
    return safe_pow(load / coeff, 1.0 / n)


def coefficient_from_overlap(load: ArrayLike, delta0: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """C = F0 / delta0^n [N/m^n], the prefactor that puts the static overlap at delta0."""
    return load / jnp.power(delta0, n)


def linear_stiffness(load: ArrayLike, delta0: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """K0 = n F0 / delta0 [N/m]."""
    return n * load / delta0


def linear_frequency(load: ArrayLike, mass: ArrayLike, delta0: ArrayLike,
                     n: ArrayLike) -> jnp.ndarray:
    """f0 = (1/2 pi) (n F0 / (m delta0))^(1/2) [Hz]."""
    return jnp.sqrt(linear_stiffness(load, delta0, n) / mass) / (2.0 * jnp.pi)


def overlap_from_frequency(f0: ArrayLike, load: ArrayLike, mass: ArrayLike,
                           n: ArrayLike) -> jnp.ndarray:
    """delta0 = n F0 / (m omega0^2) [m]; n g / omega0^2 for a weight preload."""
    return n * load / (mass * jnp.square(2.0 * jnp.pi * f0))


def frequency_from_overlap(delta0: ArrayLike, load: ArrayLike, mass: ArrayLike,
                           n: ArrayLike) -> jnp.ndarray:
    """f0 = (n F0 / (m delta0))^(1/2) / (2 pi) [Hz], the inverse of
    :func:`overlap_from_frequency`."""
    return jnp.sqrt(n * load / (mass * delta0)) / (2.0 * jnp.pi)


def _law():
    import math

    from beadrod.models.ladder.first_order import first_order_powerlaw
    from beadrod.models.law import ContactLaw, Param, Physics, Presentation, Prior
    from beadrod.models.rungs import LADDER
    from beadrod.models.tables.powerlaw_backbone import backbone_shift_clipped
    from beadrod.models.tables.surrogate import within_amplitude

    n = Param("n", "-", r"$n$", Prior("uniform", 1.0, 3.0),
              "Load-overlap exponent, F = C delta^n. Prior Uniform(1, 3): n = (1 + H)/H for "
              "Hurst exponent 0.5 <= H < inf; n = 3/2 is Hertz, n = 2 a soft oxide shell; "
              "n < 1 would soften under compression, n > 3 is beyond any self-affine surface. "
              "The law is defined for 1 < n <= 3 (n = 1 is a linear spring: no shift).",
              domain=(1.0, 3.0), open_low=True, what="the power-law exponent")
    ref = Param("delta0_ref_log", "log m", r"$\ln\delta_{0,\mathrm{ref}}$",
                Prior("normal", math.log(55e-9), 1.0),
                "Natural log of the static overlap under the weight at the nominal mount "
                "(the prefactor C is not identifiable apart from it). Prior Normal(log 55 nm, "
                "1): the Hertz overlap under the bead's weight is 50-55 nm; a rough or coated "
                "contact sits within a factor of e of it.")

    def _force(delta, *, n, delta0_ref_log, load, **_):
        return load * safe_pow(delta / jnp.exp(delta0_ref_log), n)

    return ContactLaw(
        name="powerlaw",
        params=(n, ref),
        physics=Physics(
            force=_force,
            static_overlap=lambda *, delta0_ref_log, **_: jnp.exp(delta0_ref_log),
            overlap_from_frequency=lambda f0, *, load, mass, n, **_: overlap_from_frequency(
                f0, load, mass, n),
            frequency_from_overlap=lambda d, *, load, mass, n, **_: frequency_from_overlap(
                d, load, mass, n),
            # the paper analysed this law at first order: its 'paper_eq25' rung is first order
            rungs=(*LADDER, "paper_eq25"),
            shifts={"first_order": lambda x, *, n, **_: first_order_powerlaw(x, n),
                    "paper_eq25": lambda x, *, n, **_: first_order_powerlaw(x, n),
                    "backbone": lambda x, *, n, **_: backbone_shift_clipped(x, n)},
            # the table holds its x = 2 value beyond; the inference counts no point there
            domains={"backbone": lambda x, **_: within_amplitude(x)},
        ),
        presentation=Presentation(
            label="rough power law", color="#E69F00",
            reference="paper Sec. 4.4, Eqs. 21, 26-27",
            description="F = C delta^n; the exponent n carries the roughness",
        ),
    )


LAW = _law()
"""The rough power law (:class:`models.law.ContactLaw`)."""
__all__ += ["LAW"]
