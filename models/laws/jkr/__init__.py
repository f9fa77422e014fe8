"""The JKR contact law (paper Sec. 4.3, Eqs. 16-19): :data:`LAW`, with its fast rungs.

The mechanics (closed forms in the contact radius, the root solve delta -> a, the
first-order quadrature) is :mod:`models.laws.jkr.contact` (``jkr.contact.force`` and the
rest); this module builds the law object from it. The law's first-order rung is the
table of :mod:`models.laws.jkr.table` (built from that quadrature), its backbone rung the
table of :mod:`models.tables.shape_read`; neither table module imports this one.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from beadrod.models.laws.jkr.contact import (
    force,
    overlap_from_frequency,
    static_overlap,
)
from beadrod.models.tables.shape_spec import ShapeTable, adhesive_reference_kw

__all__: list[str] = []


HERTZ_DECAY = 1.0
"""k [-] in the law's approach to Hertz's backbone as r = F0/Fc grows, ~ r^-k, used past
its table's end r = 1000 (models.tables.shape_read.backbone_fast). Measured with the generic
backbone, paper's scene: the departure at x = 1.5 and 2 is 1.85e-4, 1.84e-5, 1.84e-6 at
r = 1e3, 1e4, 1e5 (k = 1.00); below contact loss it falls faster (x = 0.9: 5.6e-6, 2.0e-7,
6e-9), so k = 1 overstates it there by at most 4e-7. Carried on from the table's end the
backbone stays within 4e-7 of the generic one at r = 1e4 (tests/test_shape_tables.py)."""
__all__ += ["HERTZ_DECAY"]



TABLE = ShapeTable(
    lambda r: adhesive_reference_kw(r, 3.0 * np.pi), float(np.log(0.3)), float(np.log(1000.0)),
    held=("r = F0/Fc > 1000 is adhesion below 0.1 % of the load, yet the table's end stands "
          "2e-4 from Hertz's backbone (carried on as 1/r: HERTZ_DECAY); r < 0.3 is "
          "gamma > 7 J/m^2 for the paper's bead"))
"""The backbone table's specification (:mod:`beadrod.models.tables.shape_build`). JKR is
universal in Maugis' reduced units (F/Fc against delta/delta_c, Fc = 3 pi gamma R): at a
given load the restoring force depends on r = F0/Fc alone, p = ln r; E* drops out. Contact
is taken to part at delta = 0, where the approach branch forms it (the snap-off hysteresis
is a loss, not a stiffness). Error against the generic exact backbone
(tests/test_shape_tables.py): within 1e-5 in Delta f/f0, except in the 0.01 of x just past
the contact-loss corner x_c, where the backbone turns by up to 30x in slope: within 1e-4
there."""
__all__ += ["TABLE"]


def _law():
    from beadrod.models.law import GAMMA, YOUNG, ContactLaw, Physics, Presentation, SamplerHints
    from beadrod.models.laws.jkr.table import X_MAX, load_ratio, shift_first_order_fast
    from beadrod.models.rungs import LADDER
    from beadrod.models.tables.shape_read import backbone_fast, in_table

    def ratio(kw):
        return load_ratio(kw["load"], gamma=kw["gamma"], radius=kw["radius"])

    def first_order(x, **kw):
        return shift_first_order_fast(jnp.clip(x, 0.0, X_MAX), ratio(kw))

    return ContactLaw(
        name="jkr",
        params=(YOUNG, GAMMA),
        physics=Physics(
            force=lambda delta, *, e_star, radius, gamma, **_: force(
                delta, e_star=e_star, radius=radius, gamma=gamma),
            static_overlap=lambda *, load, e_star, radius, gamma, **_: static_overlap(
                load, e_star=e_star, radius=radius, gamma=gamma),
            # Why not the default stiffness-scale scatter: remounting changes the elastic
            # scale E* R^(1/2) of the contact, not the adhesion gamma R; scaling the whole
            # JKR force would scale the adhesion with it. f0, F0, R and gamma fix the state.
            overlap_from_frequency=lambda f0, *, load, mass, radius, gamma, **_:
                overlap_from_frequency(f0, load, mass, radius=radius, gamma=gamma),
            # the paper analysed JKR at first order: its 'paper_eq25' rung is first order
            rungs=(*LADDER, "paper_eq25"),
            shifts={"first_order": first_order,
                    "paper_eq25": first_order,
                    "backbone": lambda x, **kw: backbone_fast("jkr", x, ratio(kw),
                                                              decay=HERTZ_DECAY)},
            # below the table's shape range, or beyond x = 2, the held value is not this
            # law's backbone: the inference counts no point there (shape_backbone.in_table);
            # above it the law tends to Hertz's as 1/r (HERTZ_DECAY)
            domains={"backbone": lambda x, **kw: in_table("jkr", x, ratio(kw),
                                                          decay=HERTZ_DECAY)},
            table=TABLE,
        ),
        presentation=Presentation(
            label="JKR adhesion", color="#D55E00",
            reference=("Johnson, Kendall & Roberts 1971; Johnson 1985 Sec. 5.5; "
                       "paper Eqs. 13-19"),
            description=("adhesive elastic sphere (large Tabor parameter); contact is taken "
                         "to part at delta = 0, where the approach branch forms it"),
        ),
        # relative fit time (models.law.SamplerHints.cost): the implicit contact-radius
        # solve and the two-parameter backbone table make its fits among the slowest
        sampler=SamplerHints(cost=4.0),
    )


LAW = _law()
"""The JKR contact law (:class:`models.law.ContactLaw`)."""
__all__ += ["LAW"]
