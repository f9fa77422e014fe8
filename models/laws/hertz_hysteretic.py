"""Hertz contact with Masing hysteresis (microslip) on its dynamic displacement.

The elastic contact is Hertz's (:mod:`models.laws.hertz`); beside it, a Masing element
(:mod:`models.laws.masing`) with virgin curve k u - a |u|^(m-1) u acts on the dynamic
displacement u = delta - delta0: microslip at the asperities or across an interface
layer, whose loops soften the contact and dissipate energy, both growing as U^(m-1).

Parameters:

* ``young`` (E), as for Hertz;
* ``strength`` h [-]: the hysteretic frequency drop at x = delta_a/delta0 = 1,
  h = -Delta k(delta0)/(2 k0), with k0 the contact's linear stiffness: the element's
  coefficient is a = 2 h k0/(c(m) delta0^(m-1))
  (:func:`models.laws.masing.coefficient_from_strength`), so h scales with the contact as
  the contact's own nonlinearity does. Prior HalfNormal(0.05):
  zero (no hysteresis, Hertz) is the mode; the paper's measured shifts reach ~0.1 at
  x = 1, of which Hertz explains ~0.05 (first order), so a hysteretic share of a few per
  cent at x = 1 is what would matter; the prior puts 32 % of its mass above 0.05 and 5 %
  above 0.1.
* ``exponent`` m [-]: the loop's power, Uniform(1.2, 3). m = 2 is Rayleigh's law and the
  small-amplitude limit of Mindlin-Deresiewicz partial slip (loss per cycle ~ U^3,
  Johnson 1985 Sec. 7.4) and of Preisach-Mayergoyz space in mesoscopic materials (Guyer &
  Johnson 2009); Segalman's power-law Iwan joints have m = 2 + chi with chi in (-1, 0);
  m = 3 is where the hysteretic shift grows as fast as Hertz's own (x^2) and beyond which
  the two cannot be told apart at small x. Below 1.2 the element is a nearly constant
  stiffness change with almost no loss (rho(m) -> 0), which the measured f0 already
  absorbs: excluded rather than left to a degenerate ridge.

Shift: at the backbone rung, the resonance of the first harmonic with both stiffnesses,
Omega^2 = (1 + s_H(x))^2 + Delta k(x)/k0 = (1 + s_H)^2 - 2 h x^(m-1), with s_H Hertz's
exact backbone; at the first-order rung both changes to first order,
Delta f/f0 = s_H(x) - h x^(m-1). Loss: the element's quadrature stiffness,
Delta(1/Q) = h rho(m) x^(m-1), added to the linear loss (:attr:`Physics.loss_increment`).
The describing function is checked against time integration of an Iwan element in
tests/test_masing.py; only the rungs with these closed forms are offered (the generic
harmonic-balance and time-integration rungs integrate the force alone, which has no
hysteresis).

Composition: one law, Hertz plus the element, rather than an element added to every
elastic law. Why: the question the element answers is whether a loss that grows with the
amplitude explains the shift beyond Hertz; the rough and adhesive laws already bend the
shift at small x by their own mechanisms, and a second mechanism on top of each would
double the comparison for no new question. The element is a module of its own, so a
user's law file can add it to any force (docs/adding-a-law.md).
"""

from __future__ import annotations

import jax.numpy as jnp
from jax.typing import ArrayLike

from beadrod.models.laws import hertz, masing

__all__ = ["shift", "shift_first_order", "loss_increment", "LAW"]


def shift(x: ArrayLike, *, elastic: ArrayLike, strength: ArrayLike,
          exponent: ArrayLike) -> jnp.ndarray:
    """Delta f/f0 = sqrt((1 + s_H)^2 - 2 h x^(m-1)) - 1 [-], with ``elastic`` the elastic
    law's shift s_H at x (the stiffness ratio bounded below by 1e-6: a point that drives it
    to zero is far outside any prior region the data allow).

    Written as s_H + dk/(sqrt((1 + s_H)^2 + dk) + 1 + s_H), dk = Delta k/k0, so that zero
    strength gives s_H exactly (no round-off of the square root) and the derivative in h
    there is the first-order one."""
    one = 1.0 + jnp.asarray(elastic)
    dk = masing.stiffness_change(x, strength=strength, exponent=exponent)
    root = jnp.sqrt(jnp.maximum(jnp.square(one) + dk, 1e-6))
    return jnp.asarray(elastic) + dk / (root + one)


def shift_first_order(x: ArrayLike, *, elastic: ArrayLike, strength: ArrayLike,
                      exponent: ArrayLike) -> jnp.ndarray:
    """Delta f/f0 = s_H - h x^(m-1) [-]: both stiffness changes to first order."""
    return jnp.asarray(elastic) + masing.shift_first_order(x, strength=strength,
                                                           exponent=exponent)


def loss_increment(x: ArrayLike, *, strength: ArrayLike, exponent: ArrayLike) -> jnp.ndarray:
    """Delta(1/Q) = h rho(m) x^(m-1) [-]: the element's quadrature stiffness over k0."""
    return masing.loss_change(x, strength=strength, exponent=exponent)


def _law():
    from beadrod.models.ladder.first_order import first_order_hertz
    from beadrod.models.law import YOUNG, ContactLaw, Param, Physics, Presentation, Prior
    from beadrod.models.tables.powerlaw_backbone import backbone_shift_clipped
    from beadrod.models.tables.surrogate import within_amplitude

    strength = Param(
        "strength", "1", r"$h$", Prior("halfnormal", 0.05),
        "Hysteretic frequency drop at x = delta_a/delta0 = 1 (the Masing element's "
        "strength, made dimensionless by the contact's linear stiffness). Prior "
        "HalfNormal(0.05): no hysteresis is the mode; a share of a few per cent of the "
        "shift at x = 1 is what could matter.", what="the hysteretic strength")
    exponent = Param(
        "exponent", "1", r"$m$", Prior("uniform", 1.2, 3.0),
        "Power of the Masing loop (loss per cycle ~ U^(m+1)); m = 2 is Rayleigh's law and "
        "Mindlin partial slip. Prior Uniform(1.2, 3): below, the element is a constant "
        "stiffness change without loss; above 3 it softens like Hertz itself.",
        what="the hysteresis exponent")

    def with_loops(elastic, combine):
        return lambda x, *, strength, exponent, **kw: combine(
            x, elastic=elastic(x, **kw), strength=strength, exponent=exponent)

    return ContactLaw(
        name="hertz_hysteretic",
        params=(YOUNG, strength, exponent),
        physics=Physics(
            **hertz.mechanics(),
            rungs=("first_order", "backbone"),
            shifts={"first_order": with_loops(lambda x, **_: first_order_hertz(x),
                                              shift_first_order),
                    "backbone": with_loops(
                        lambda x, **_: backbone_shift_clipped(x, hertz.EXPONENT), shift)},
            domains={"backbone": lambda x, **_: within_amplitude(x)},
            loss_increment=lambda x, *, strength, exponent, **_: loss_increment(
                x, strength=strength, exponent=exponent),
        ),
        presentation=Presentation(
            label="Hertz + hysteresis", color="#44AA99",
            reference="Masing 1926; Iwan 1966; Guyer & Johnson 2009; Johnson 1985 Sec. 7.4",
            description=("Hertz plus a Masing (microslip) element on the dynamic "
                         "displacement: shift and loss both grow as x^(m-1)"),
        ),
    )


LAW = _law()
"""Hertz with Masing hysteresis (:class:`models.law.ContactLaw`)."""
