"""beadrod physics: pure JAX, float64-ready contact mechanics of a bead on a rod.

Nothing here touches global JAX configuration: entry points (the ``beadrod`` CLI,
``tests/conftest.py``) switch float64 on. The parts:

* the law API: :mod:`.law` (the :class:`~.law.ContactLaw` object), :mod:`.registry` (the one
  list of laws and of rungs), :mod:`.rungs`, :mod:`.lawfile` (laws users write), :mod:`.nominal`;
* :mod:`.laws`: one module per contact law, a folder for a law with several;
* :mod:`.ladder`: the accuracy ladder and its numerics;
* :mod:`.tables`: stored tables and the surrogates read from them;
* :mod:`.scene`: a concrete setup, what it calls for (the plan) and its simulation.

Submodules load on first use (``beadrod.models.rungs`` can be read without starting JAX).
"""

import importlib

__all__ = ["law", "registry", "rungs", "lawfile", "nominal", "safe_math", "tomlfile",
           "laws", "ladder", "tables", "scene"]


def __getattr__(name: str):
    if name in __all__:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
