"""beadrod physics: pure JAX, float64-ready contact mechanics of a bead on a rod.

Nothing here touches global JAX configuration: entry points (the ``beadrod``
CLI, ``tests/conftest.py``) switch float64 on. Modules are imported as
namespaces, one per contact law, e.g. ``from models import hertz``.
"""

from . import hertz, materials, powerlaw

__all__ = ["hertz", "materials", "powerlaw"]
