"""The Maugis-Dugdale contact law (JKR-DMT transition): :data:`LAW`, with its fast rungs.

The mechanics (Maugis' parametric solution in the angle theta, the root solves, the
first-order quadrature) is :mod:`models.laws.maugis_dugdale.contact`
(``maugis_dugdale.contact.force`` and the rest); this module builds the law object from it.
At a given load the shape
of F(delta)/F0 against delta/delta0 depends on two numbers only, the load ratio F0/Fc
(equivalently Pbar0 = F0/(pi w R)) and lam: the static state is tabulated in them
(:mod:`models.laws.maugis_dugdale.static`), the backbone too (a table of
:mod:`models.tables.shape_build` with two shape coordinates), and the generic exact backbone it
is built from averages the force in parametric form (:mod:`models.laws.maugis_dugdale.orbit`).
None of these imports this module.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from beadrod.models.laws.maugis_dugdale.contact import (
    force,
    reduced_pull_off,
)
from beadrod.models.tables.shape_spec import ShapeTable

__all__: list[str] = []


HERTZ_DECAY = 1.0
"""k [-] in the law's approach to Hertz's backbone as r = F0/Fc grows, ~ r^-k, used past
its table's end r = 1000 (models.tables.shape_read.backbone_fast). Measured with the generic
backbone, paper's scene, past contact loss (x = 1.5): 1.85e-4 and 1.84e-5 at r = 1e3 and
1e4 for lam = 3.16 (k = 1.00), 1.49e-4 and 1.45e-5 for lam = 0.1 (k = 1.01), 1.86e-4 and
1.86e-5 for lam = 100 (k = 1.00); below contact loss it falls faster (lam = 0.1, x = 0.9:
1.6e-5, 7.4e-7), where k = 1 overstates it by at most 9e-7 at r = 1e4
(tests/test_shape_tables.py)."""
__all__ += ["HERTZ_DECAY"]



def _table_kw(r, lam):
    # units with K = 4 E*/3 = 1, R = 1, pi w R = 1 (so a_s = d_s = F_s = 1): the load is
    # r times the pull-off force -Pbar_c(lam)
    lam = jnp.asarray(lam, float)
    return {"load": -jnp.asarray(r, float) * reduced_pull_off(lam), "radius": 1.0,
            "e_star": 0.75, "gamma": 0.5 / np.pi, "lam": lam, "mass": 1.0}


TABLE = ShapeTable(
    _table_kw, float(np.log(0.3)), float(np.log(1000.0)),
    held=("as for JKR, with Fc the Maugis-Dugdale pull-off force (3 pi gamma R to "
          "4 pi gamma R); lambda outside [0.1, 100] (the prior's range) is outside the table"),
    # the second coordinate, ln lambda: the shape moves from DMT-like to JKR-like
    # across lambda ~ 0.3-3; its Chebyshev terms fall to ~1e-7 of S by the 16th
    q_range=(float(np.log(0.1)), float(np.log(100.0))), m_q=20)
"""The backbone table's specification (:mod:`beadrod.models.tables.shape_build`): two shape
coordinates, p = ln(F0/Fc) with Fc the pull-off force, and q = ln lam in [ln 0.1, ln 100].
Stated error as for JKR: 1e-5 in Delta f/f0 away from the contact-loss corner, 1e-4 in the
0.01 of x past it (tests/test_shape_tables.py)."""
__all__ += ["TABLE"]


def _law():
    from beadrod.models.law import (
        GAMMA,
        YOUNG,
        ContactLaw,
        Param,
        Physics,
        Prepared,
        Presentation,
        Prior,
        SamplerHints,
    )
    from beadrod.models.laws.maugis_dugdale import orbit, static
    from beadrod.models.tables.shape_read import backbone_fast, in_table

    lam = Param("lam", "-", r"$\lambda$", Prior("loguniform", *static.LAM_RANGE),
                "Maugis transition parameter lambda = sigma0 (9R/(2 pi w E*^2))^(1/3). Prior "
                "LogUniform(0.1, 100): from DMT-like (lambda < 0.1) to JKR-like (> 5) "
                "contacts; a Lennard-Jones gap z0 = 0.4 nm gives lambda ~ 30 for the paper's "
                "bead. The law is defined on the prior's range only (its static state is "
                "tabulated there, models.laws.maugis_dugdale.static; NaN outside).",
                domain=static.LAM_RANGE, what="the Maugis transition parameter")

    # the static state (r, ln n, ln D, Pbar_c) is read by the overlap maps, the reference
    # overlap, the backbone and its domain: computed once per resolve, not by each
    state = Prepared("maugis_dugdale_state", ("load", "radius", "gamma", "lam"),
                     lambda *, load, radius, gamma, lam, **_: static.contact_state(
                         load, radius=radius, gamma=gamma, lam=lam))
    held = state.value

    def ratio(kw):
        return held(kw)[0]

    return ContactLaw(
        name="maugis_dugdale",
        params=(YOUNG, GAMMA, lam),
        physics=Physics(
            force=lambda delta, *, e_star, radius, gamma, lam, **_: force(
                delta, e_star=e_star, radius=radius, gamma=gamma, lam=lam),
            # the static state from tables in (F0/Fc, lam) (models.laws.maugis_dugdale.static:
            # every load, lam on the law's domain; no root solve in a sampler's program)
            static_overlap=lambda **kw: static.static_overlap(
                kw["load"], e_star=kw["e_star"], radius=kw["radius"], gamma=kw["gamma"],
                lam=kw["lam"], state=held(kw)),
            # the elastic scale E* R^(1/2) scatters between mounts, not the adhesion (as JKR)
            overlap_from_frequency=lambda f0, **kw: static.overlap_from_frequency(
                f0, kw["load"], kw["mass"], radius=kw["radius"], gamma=kw["gamma"],
                lam=kw["lam"], state=held(kw)),
            frequency_from_overlap=lambda delta0, **kw: static.frequency_from_overlap(
                delta0, kw["load"], kw["mass"], radius=kw["radius"], gamma=kw["gamma"],
                lam=kw["lam"], state=held(kw)),
            # the generic backbone averages the force over intervals: along the branch in
            # theta the state is explicit, so no root solve per force
            # (models.laws.maugis_dugdale.orbit)
            restoring_force=orbit.restoring_force,
            shifts={"backbone": lambda x, **kw: backbone_fast("maugis_dugdale", x, ratio(kw),
                                                              kw["lam"], decay=HERTZ_DECAY)},
            # below the table's load ratios, outside its lam range or beyond x = 2 the held
            # value is not this law's backbone: the inference counts no point there; above
            # them the law tends to Hertz's as 1/r (HERTZ_DECAY)
            domains={"backbone": lambda x, **kw: in_table("maugis_dugdale", x, ratio(kw),
                                                          kw["lam"], decay=HERTZ_DECAY)},
            table=TABLE,
            prepared=(state,),
        ),
        presentation=Presentation(
            label="Maugis-Dugdale adhesion", color="#882255",
            reference=("Maugis 1992, J. Colloid Interface Sci. 150, 243; "
                       "Johnson & Greenwood 1997"),
            description=("adhesion between the JKR and DMT limits (Dugdale cohesive zone); "
                         "its backbone is a table in (F0/Fc, lambda), its first order the "
                         "generic quadrature (exact, slow in a sampler); contact is taken to "
                         "part at delta = 0, as for JKR and DMT"),
        ),
        sampler=SamplerHints(
            # the data fix the pull-off force Fc = -Pbar_c(lam) pi w R (through F0/Fc), not
            # gamma itself: over lam's prior Pbar_c runs from -2 (DMT-like) to -3/2
            # (JKR-like), so gamma's posterior follows a curved ridge over ln lam, which NUTS
            # crosses slowly (on data simulated at lam = 1, one chain in four not at all).
            # Sampled as gamma |Pbar_c(lam)| the ridge is straight (tests/test_recovery.py)
            scales={"gamma": lambda *, lam, **_: -static.pull_off(lam)},
            # relative fit time (models.law.SamplerHints.cost): the costliest law, started
            # first. Its curve depends on two parameters, so inference.speed.fold does not
            # fold it; its sweeps' likelihood is folded instead
            # (inference.speed.residual_fold, built in the mode search)
            cost=5.0,
        ),
    )


LAW = _law()
"""The Maugis-Dugdale contact law (:class:`models.law.ContactLaw`)."""
__all__ += ["LAW"]
