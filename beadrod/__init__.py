"""beadrod: Bayesian model comparison and parameter inference for a bead resting on a rod.

The notebook API (each name documented with an example; workflows/api.py)::

    import beadrod
    ds = beadrod.load_dataset("paper_like")      # an embedded world, or a dataset folder
    res = beadrod.compare(ds, laws=["hertz", "powerlaw", "baseline"],
                          chains=2, warmup=100, samples=100)
    res.table                                    # the comparison as a DataFrame
    res.report("beadrod-out")                    # report.html, tables, figures

The packages: ``beadrod.models`` (contact laws and their physics, pure JAX),
``beadrod.data`` (datasets: load, validate, simulate), ``beadrod.inference`` (NumPyro
models, sampling, evidence) and ``beadrod.workflows`` (the ``beadrod`` command line and
the API). ``import beadrod`` imports none of them: a name of the API imports its module
when first used, and JAX starts only when a function computes.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["load_dataset", "worlds", "laws", "fit", "compare", "shift", "simulate",
           "ComparisonResult", "UserError", "DataError"]

# name -> the module that defines it (read on first use: importing JAX takes seconds)
_HOME = {name: "beadrod.workflows.api" for name in __all__}
_HOME["DataError"] = "beadrod.data.schema"


def __getattr__(name: str) -> Any:
    if name not in _HOME:
        raise AttributeError(f"module 'beadrod' has no attribute {name!r}")
    value = getattr(importlib.import_module(_HOME[name]), name)
    globals()[name] = value  # looked up once
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
