"""DMT adhesive contact: the stiff, short-range end of the adhesion map (mu << 1).

Derjaguin, Muller & Toporov, J. Colloid Interface Sci. 53, 314 (1975), in the form of
Maugis, *Contact, Adhesion and Rupture of Elastic Solids* (Springer 2000), Sec. 5 and
Johnson & Greenwood, J. Colloid Interface Sci. 192, 326 (1997): the contact keeps the
Hertz profile and the adhesion adds a constant attraction acting just outside it,

    F(delta) = (4/3) E* R^(1/2) delta^(3/2) - 2 pi w R,    w = 2 gamma (identical surfaces),
    pull-off force Fc = 2 pi w R = 4 pi gamma R (at a = 0, delta = 0),
    a = (R delta)^(1/2),  K = dF/d(delta) = 2 E* a = Hertz stiffness,
    delta0 = Hertz overlap under F0 + 2 pi w R.

Convention: gamma [J/m^2] is each surface's energy, as in models.laws.jkr (whose pull-off is
(3/2) pi w R = 3 pi gamma R). The finite-range attraction outside contact (delta < 0) is
neglected: force and stiffness are 0 for delta <= 0 (a hard-wall simplification; the force
therefore jumps by Fc at delta = 0, the DMT snap).
"""

from __future__ import annotations

import sys

import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.ladder.first_order import first_order_adhesive
from beadrod.models.laws import hertz
from beadrod.models.safe_math import safe_pow, safe_sqrt
from beadrod.models.tables.shape_spec import ShapeTable, adhesive_reference_kw

__all__ = [
    "pull_off_force",
    "contact_radius",
    "overlap_from_contact_radius",
    "force_from_contact_radius",
    "stiffness_from_contact_radius",
    "contact_radius_from_overlap",
    "static_overlap",
    "linear_stiffness",
    "linear_frequency",
    "stiffness",
    "force",
    "shift_first_order",
    "overlap_from_frequency",
    "frequency_from_overlap",
]


def pull_off_force(*, gamma: ArrayLike, radius: ArrayLike) -> jnp.ndarray:
    """Fc = 2 pi w R = 4 pi gamma R [N]."""
    return 4.0 * jnp.pi * gamma * radius


def contact_radius(
    load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """a = (3 R (F + Fc)/(4 E*))^(1/3) [m]; 0 for F <= -Fc (separated)."""
    fc = pull_off_force(gamma=gamma, radius=radius)
    return safe_pow(0.75 * radius * (load + fc) / e_star, 1.0 / 3.0)


def overlap_from_contact_radius(
    a: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """delta = a^2/R [m] (Hertz profile; E* and gamma do not enter)."""
    del e_star, gamma
    return jnp.square(a) / radius


def force_from_contact_radius(
    a: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """F = 4 E* a^3/(3R) - Fc [N]."""
    return 4.0 * e_star * safe_pow(a, 3.0) / (3.0 * radius) - pull_off_force(
        gamma=gamma, radius=radius
    )


def stiffness_from_contact_radius(
    a: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """K = 2 E* a [N/m] (gamma does not enter)."""
    del radius, gamma
    return 2.0 * e_star * jnp.maximum(jnp.asarray(a), 0.0)


def contact_radius_from_overlap(
    delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """a = (R delta)^(1/2) [m]; 0 for delta <= 0. Closed form: no root solve needed."""
    del e_star, gamma
    return safe_sqrt(radius * jnp.asarray(delta))


def static_overlap(
    load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """delta0 = Hertz overlap under F0 + Fc [m]."""
    fc = pull_off_force(gamma=gamma, radius=radius)
    return hertz.static_overlap(load + fc, e_star=e_star, radius=radius)


def linear_stiffness(
    load: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """K0 = 2 E* (R delta0)^(1/2) = (3/2)(F0 + Fc)/delta0 [N/m]."""
    d0 = static_overlap(load, e_star=e_star, radius=radius, gamma=gamma)
    return hertz.stiffness(d0, e_star=e_star, radius=radius)


def linear_frequency(
    load: ArrayLike, mass: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """f0 = (1/2 pi)(K0/m)^(1/2) [Hz]."""
    k0 = linear_stiffness(load, e_star=e_star, radius=radius, gamma=gamma)
    return safe_sqrt(k0 / mass) / (2.0 * jnp.pi)


def stiffness(
    delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """K(delta) = 2 E* (R delta)^(1/2) [N/m]; 0 for delta <= 0."""
    del gamma
    return hertz.stiffness(delta, e_star=e_star, radius=radius)


def force(
    delta: ArrayLike, *, e_star: ArrayLike, radius: ArrayLike, gamma: ArrayLike
) -> jnp.ndarray:
    """F(delta) = F_Hertz(delta) - Fc for delta > 0, 0 for delta <= 0 [N]."""
    delta = jnp.asarray(delta)
    f = hertz.force(delta, e_star=e_star, radius=radius) - pull_off_force(
        gamma=gamma, radius=radius
    )
    return jnp.where(delta > 0, f, 0.0)


def shift_first_order(
    x: ArrayLike,
    *,
    load: ArrayLike,
    e_star: ArrayLike,
    radius: ArrayLike,
    gamma: ArrayLike,
    reference_overlap: ArrayLike | None = None,
) -> jnp.ndarray:
    """First-order Delta f/f0 [-], x = delta_a/delta_ref (delta_ref defaults to the DMT delta0).

    With x normalised by the DMT delta0 this is exactly the Hertz first-order shift (the
    stiffness is Hertz's); computed by quadrature through models.ladder.first_order for uniformity.
    """
    return first_order_adhesive(sys.modules[__name__], x, load=load, e_star=e_star,
                                radius=radius, gamma=gamma, reference_overlap=reference_overlap)


def overlap_from_frequency(
    f0: ArrayLike,
    load: ArrayLike,
    mass: ArrayLike,
    *,
    radius: ArrayLike,
    gamma: ArrayLike,
    e_star: ArrayLike | None = None,
) -> jnp.ndarray:
    """delta0 = 3 (F0 + Fc)/(2 m (2 pi f0)^2) [m], independent of E* (as for Hertz).

    ``e_star`` is accepted for signature compatibility and not used.
    """
    del e_star
    fc = pull_off_force(gamma=gamma, radius=radius)
    return 1.5 * (load + fc) / (mass * jnp.square(2.0 * jnp.pi * f0))


def frequency_from_overlap(delta0: ArrayLike, load: ArrayLike, mass: ArrayLike, *,
                           radius: ArrayLike, gamma: ArrayLike) -> jnp.ndarray:
    """f0 = (3 (F0 + Fc) / (2 m delta0))^(1/2) / (2 pi) [Hz], the inverse of
    :func:`overlap_from_frequency`."""
    fc = pull_off_force(gamma=gamma, radius=radius)
    return jnp.sqrt(1.5 * (load + fc) / (mass * delta0)) / (2.0 * jnp.pi)


HERTZ_DECAY = 1.0
"""k [-] in the law's approach to Hertz's backbone as r = F0/Fc grows, ~ r^-k, used past
its table's end r = 1000 (models.tables.shape_read.backbone_fast). Measured with the generic
backbone, paper's scene: in contact DMT's backbone is Hertz's (to 5e-10); past contact
loss the departure at x = 1.5 and 2 is 2.79e-4 and 2.79e-5 at r = 1e3 and 1e4 (k = 1.00).
Carried on from the table's end the backbone stays within 2e-7 of the generic one at
r = 1e4 (tests/test_shape_tables.py)."""
__all__ += ["HERTZ_DECAY"]



TABLE = ShapeTable(
    lambda r: adhesive_reference_kw(r, 4.0 * np.pi), float(np.log(0.3)), float(np.log(1000.0)),
    held="as for JKR, with Fc = 4 pi gamma R (carried on past r = 1000: HERTZ_DECAY)")
"""The backbone table's specification (:mod:`beadrod.models.tables.shape_build`). DMT's
restoring force is Hertz's inside contact, (2/3)((1+q)^(3/2) - 1); only its flight
acceleration (2/3) F0/(F0 + Fc), Fc = 4 pi gamma R, depends on r = F0/Fc (p = ln r); E*
drops out. Contact
is taken to part at delta = 0, where the approach branch forms it (the snap-off hysteresis
is a loss, not a stiffness). Error against the generic exact backbone
(tests/test_shape_tables.py): within 1e-5 in Delta f/f0, except in the 0.01 of x just past
the contact-loss corner x_c, where the backbone turns by up to 30x in slope: within 1e-4
there."""
__all__ += ["TABLE"]


def _law():
    from beadrod.models.ladder.first_order import first_order_hertz
    from beadrod.models.law import GAMMA, YOUNG, ContactLaw, Physics, Presentation, SamplerHints
    from beadrod.models.tables.powerlaw_backbone import X_MAX
    from beadrod.models.tables.shape_read import backbone_fast, in_table

    def ratio(kw):
        return kw["load"] / pull_off_force(gamma=kw["gamma"], radius=kw["radius"])

    return ContactLaw(
        name="dmt",
        params=(YOUNG, GAMMA),
        physics=Physics(
            force=lambda delta, *, e_star, radius, gamma, **_: force(
                delta, e_star=e_star, radius=radius, gamma=gamma),
            static_overlap=lambda *, load, e_star, radius, gamma, **_: static_overlap(
                load, e_star=e_star, radius=radius, gamma=gamma),
            # the elastic scale E* R^(1/2) scatters, not the adhesion (as for JKR)
            overlap_from_frequency=lambda f0, *, load, mass, radius, gamma, **_:
                overlap_from_frequency(f0, load, mass, radius=radius, gamma=gamma),
            frequency_from_overlap=lambda d, *, load, mass, radius, gamma, **_:
                frequency_from_overlap(d, load, mass, radius=radius, gamma=gamma),
            # first order: the DMT stiffness is Hertz's, so in x = delta_a/delta0 (the DMT
            # overlap) the average is exactly the Hertz one
            shifts={"first_order": lambda x, **_: first_order_hertz(jnp.clip(x, 0.0, X_MAX)),
                    "backbone": lambda x, **kw: backbone_fast("dmt", x, ratio(kw),
                                                              decay=HERTZ_DECAY)},
            # below the table's shape range, or beyond x = 2, the held value is not this
            # law's backbone: the inference counts no point there (shape_backbone.in_table);
            # above it the law tends to Hertz's as 1/r (HERTZ_DECAY)
            domains={"backbone": lambda x, **kw: in_table("dmt", x, ratio(kw),
                                                          decay=HERTZ_DECAY)},
            table=TABLE,
        ),
        presentation=Presentation(
            label="DMT adhesion", color="#CC79A7",
            reference="Derjaguin, Muller & Toporov 1975; Maugis 2000 Sec. 4",
            description=("adhesive elastic sphere (small Tabor parameter): Hertz stiffness "
                         "under the load plus the pull-off force 4 pi gamma R"),
        ),
        # relative fit time (models.law.SamplerHints.cost): two-parameter backbone table
        sampler=SamplerHints(cost=2.0),
    )


LAW = _law()
"""The DMT contact law (:class:`models.law.ContactLaw`)."""
__all__ += ["LAW"]
