"""beadrod physics: pure JAX, float64-ready contact mechanics of a bead on a rod.

Nothing here touches global JAX configuration: entry points (the ``beadrod`` CLI,
``tests/conftest.py``) switch float64 on. Modules are namespaces, one per contact law or
rung, e.g. ``from models import hertz, shift, backbone``; :mod:`models.registry` is the
one list of contact laws and :mod:`models.rungs` of rungs. Submodules load on first use,
so ``models.rungs`` can be read without starting JAX.
"""

import importlib

__all__ = [
    "adhesion", "autotable", "backbone", "backbone_table", "dmt", "generic",
    "greenwood_williamson", "hbm", "hertz", "jkr", "jkr_contact", "jkr_table", "ladder", "law",
    "lawfile", "materials", "maugis_dugdale", "oscillator", "plan", "powerlaw", "registry",
    "rod", "rungs", "scenes", "shape_backbone", "shape_tables", "shift", "simulate",
    "surrogate", "timeint", "viscoelastic",
]


def __getattr__(name: str):
    if name in __all__:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module 'models' has no attribute {name!r}")
