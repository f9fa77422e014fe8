"""The contact laws, one module each; a law with several modules has a folder of its own.

Each module defines ``LAW`` (a :class:`beadrod.models.law.ContactLaw`); :data:`BUILTIN`
lists them in the order every table shows them, and :mod:`beadrod.models.registry` serves
them (with the laws users load from files). This folder is the only place in
``beadrod.models`` that names a law.
"""

from beadrod.models.laws import (
    dmt,
    greenwood_williamson,
    hertz,
    hertz_hysteretic,
    jkr,
    maugis_dugdale,
    powerlaw,
    viscoelastic,
)

__all__ = ["BUILTIN"]

BUILTIN = (hertz.LAW, powerlaw.LAW, viscoelastic.LAW, viscoelastic.SPLIT_LAW,
           hertz_hysteretic.LAW, jkr.LAW, dmt.LAW, greenwood_williamson.LAW,
           maugis_dugdale.LAW)
"""The built-in laws, in the order every table and figure shows them."""
