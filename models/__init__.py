"""beadrod physics: pure JAX, float64-ready contact mechanics of a bead on a rod.

Nothing here touches global JAX configuration: entry points (the ``beadrod``
CLI, ``tests/conftest.py``) switch float64 on. Modules are namespaces, one per
contact law or rung, e.g. ``from models import hertz, shift, backbone``;
:mod:`models.registry` is the one list of contact laws.
"""

from . import (
    adhesion,
    backbone,
    backbone_table,
    dmt,
    hbm,
    hertz,
    jkr,
    ladder,
    materials,
    oscillator,
    plan,
    powerlaw,
    registry,
    rod,
    scenes,
    shift,
    simulate,
    timeint,
    viscoelastic,
)

__all__ = [
    "adhesion",
    "backbone",
    "backbone_table",
    "dmt",
    "hbm",
    "hertz",
    "jkr",
    "ladder",
    "materials",
    "oscillator",
    "plan",
    "powerlaw",
    "registry",
    "rod",
    "scenes",
    "shift",
    "simulate",
    "timeint",
    "viscoelastic",
]
