"""Contact laws that users write themselves, one Python file each (``--law-file FILE.py``).

The contract (docs/adding-a-law.md has an example):

* ``NAME`` (str, a new law name: letters, digits, ``_``); optional ``LABEL``, ``REFERENCE``,
  ``DESCRIPTION`` (str) and ``ADHESIVE`` (bool, default False);
* ``PRIORS``: a dict from each law parameter to a proper prior (a NumPyro distribution,
  or a :class:`models.law.Prior`);
* ``force(delta, *, ...)``: JAX-traceable, overlap delta [m] -> force F [N] (compressive
  > 0), zero for delta <= 0 unless ``ADHESIVE``. Its keyword arguments are law parameters
  (keys of ``PRIORS``) or scene quantities passed by name
  (:data:`models.law.SCENE_KEYS`: radius, young, poisson, e_star, load, mass, gravity,
  roughness_rms, surface_energy).

The file's law gets every rung the generic numerics give (first order, backbone), the
default protocol-scatter treatment (a stiffness scale per protocol) and, when its
dimensionless backbone turns out not to depend on its parameters or the overlap (a
shape-invariant law, such as a Hertz written from scratch), a fast table built on load
(:mod:`models.autotable`). A file that breaks the contract raises :class:`LawFileError`
naming the file and what is wrong.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import inspect
import math
import re
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .autotable import attach_fast_backbone
from .law import SCENE_KEYS, YOUNG, ContactLaw, Param, Prior, prior_median

__all__ = ["LawFileError", "load_law_file"]

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


class LawFileError(ValueError):
    """A law file that breaks the contract (the message names the file)."""


def _fail(path: Path, what: str) -> LawFileError:
    return LawFileError(f"law file {path}: {what}")


def _module(path: Path):
    if not path.is_file():
        raise _fail(path, "no such file")
    spec = importlib.util.spec_from_file_location(f"beadrod_user_law_{path.stem}", path)
    if spec is None or spec.loader is None:
        raise _fail(path, "cannot be imported as Python")
    mod = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(mod)
    except Exception as exc:  # noqa: BLE001  (the user's code: report, do not crash)
        raise _fail(path, f"raised {type(exc).__name__} on import: {exc}") from exc
    return mod


def _check_prior(path: Path, name: str, prior: Any) -> None:
    if isinstance(prior, Prior):
        return
    if not (hasattr(prior, "log_prob") and hasattr(prior, "sample")):
        raise _fail(path, f"PRIORS[{name!r}] is not a distribution (got "
                          f"{type(prior).__name__})")
    med = prior_median(prior)
    if not math.isfinite(med):
        raise _fail(path, f"PRIORS[{name!r}] has no finite median (improper prior?)")


def load_law_file(path: str | Path, scene: dict[str, float]) -> ContactLaw:
    """The :class:`ContactLaw` that the file at ``path`` defines, checked against the
    contract at the scene quantities ``scene`` and the prior medians."""
    path = Path(path)
    mod = _module(path)
    name = getattr(mod, "NAME", None)
    if not isinstance(name, str) or not _NAME.match(name):
        raise _fail(path, "NAME is missing or not a name (letters, digits, _; e.g. "
                          "NAME = \"my_law\")")
    priors = getattr(mod, "PRIORS", None)
    if not isinstance(priors, dict):
        raise _fail(path, "PRIORS is missing (a dict from each law parameter to a prior)")
    force = getattr(mod, "force", None)
    if not callable(force):
        raise _fail(path, "force(delta, *, ...) is missing")
    sig = inspect.signature(force)
    params = list(sig.parameters.values())
    if not params or params[0].kind not in (params[0].POSITIONAL_ONLY,
                                            params[0].POSITIONAL_OR_KEYWORD):
        raise _fail(path, "force must take the overlap delta [m] as its first argument")
    keys = [p.name for p in params[1:]]
    for k in keys:
        if k not in priors and k not in SCENE_KEYS:
            raise _fail(path, f"force's argument {k!r} has no prior in PRIORS and is not a "
                              f"scene quantity ({', '.join(SCENE_KEYS)})")
    for k, pr in priors.items():
        if k in SCENE_KEYS and k != YOUNG.name:
            raise _fail(path, f"PRIORS[{k!r}] shadows a scene quantity: rename it")
        if k not in keys:
            raise _fail(path, f"PRIORS[{k!r}] is not an argument of force")
        _check_prior(path, k, pr)

    def user_force(delta, **kw):
        return force(delta, **{k: kw[k] for k in keys})

    # a fitted E (the one scene quantity a file may fit) is the built-in laws' E with the
    # file's prior: its unit, label, scene value and physical bounds come from YOUNG
    law_params = tuple(
        dataclasses.replace(YOUNG, prior=pr, description="law-file parameter: Young's "
                            "modulus, with the file's prior") if k == YOUNG.name else
        Param(k, "?", k, pr, f"law-file parameter {k}") for k, pr in priors.items())
    law = ContactLaw(
        name=name, label=str(getattr(mod, "LABEL", name)),
        reference=str(getattr(mod, "REFERENCE", f"user law file {path.name}")),
        description=str(getattr(mod, "DESCRIPTION", "")), params=law_params,
        force=user_force, source=str(path))
    _check_force(path, law, scene, adhesive=bool(getattr(mod, "ADHESIVE", False)))
    return attach_fast_backbone(law, scene)


def _check_force(path: Path, law: ContactLaw, scene: dict[str, float], *,
                 adhesive: bool) -> None:
    theta = {p.name: prior_median(p.prior) for p in law.params}
    kw = law.resolve(scene, theta)
    try:
        d0 = float(law.overlap(**kw))
        f0, k0 = (float(v) for v in jax.jvp(lambda d: law.force(d, **kw), (jnp.asarray(d0),),
                                            (jnp.asarray(1.0),)))
        f_neg = float(law.force(jnp.asarray(-0.5 * d0), **kw))
    except Exception as exc:  # noqa: BLE001
        raise _fail(path, f"force raised {type(exc).__name__}: {exc}") from exc
    where = f"at the prior medians {theta}"
    if not (np.isfinite(f0) and np.isfinite(k0)):
        raise _fail(path, f"NaN or infinite force or stiffness at the static overlap "
                          f"{d0:.4g} m {where}")
    if not (np.isfinite(d0) and abs(f0 - kw["load"]) <= 1e-6 * abs(kw["load"])):
        raise _fail(path, f"no static overlap under the load {kw['load']:.4g} N {where} "
                          "(force must increase through the load for 1e-14 < delta < 1e-2 m)")
    if k0 <= 0:
        raise _fail(path, f"stiffness dF/d delta = {k0:.4g} N/m <= 0 at the static overlap "
                          f"{where}: no stable equilibrium")
    if not adhesive and f_neg != 0.0:
        raise _fail(path, f"force({-0.5 * d0:.3g} m) = {f_neg:.4g} N: it must be zero for "
                          "delta <= 0 (contact lost) unless ADHESIVE = True")
