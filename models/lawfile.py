"""Contact laws that users write themselves, one Python file each (``--law-file FILE.py``).

The contract (docs/adding-a-law.md has an example):

* ``NAME`` (str, a new law name: a letter, then letters, digits or ``_``, at most
  :data:`NAME_MAX` characters, since it names the run's files ``laws/NAME.json``,
  ``idata/NAME.nc``; not a registered law's name, in any case, nor one of the names the
  caller reserves, such as the law-free baseline's); optional ``LABEL`` (str, one line),
  ``REFERENCE``, ``DESCRIPTION`` (str) and ``ADHESIVE`` (bool, default False);
* ``PRIORS``: a dict from each law parameter to a proper scalar prior with an inverse
  CDF (a NumPyro distribution with ``icdf``, no batch or event shape; or a
  :class:`models.law.Prior`): nested sampling and the prior tables map [0, 1] through it;
* ``force(delta, *, ...)``: JAX-traceable, overlap delta [m] -> force F [N] (compressive
  > 0), zero for delta <= 0 unless ``ADHESIVE``. Its keyword arguments are law parameters
  (keys of ``PRIORS``) or scene quantities passed by name
  (:data:`models.law.SCENE_KEYS`: radius, young, poisson, e_star, load, mass, gravity,
  roughness_rms, surface_energy);
* optional, the law's own loss (docs/damping.md), which the amplitude likelihood reads
  (:meth:`models.law.ContactLaw.loss`): ``LOSS_EXPONENT`` (a finite real >= 0), how its
  linear loss scales with the resonance, L0 Omega^beta (with it the comparison fits no
  background exponent for this law; without it, beta is fitted), and
  ``loss_increment(x, *, ...)``, JAX-traceable, the loss Delta(1/Q) >= 0 it adds at the
  amplitude x = delta_a/delta0, with keyword arguments as ``force``'s. It is checked at
  the prior medians for finite values >= 0 at x = 0 ... 2, zero at x = 0 (the linear
  loss is the reference Q's), and finite gradients there in
  the law's parameters (and in x for x > 0): write a power of x with a double ``where``
  at x = 0. Every key of ``PRIORS`` is an argument of ``force`` or of ``loss_increment``.

The file's law gets every rung the generic numerics give (first order, backbone), the
default protocol-scatter treatment (a stiffness scale per protocol) and, when its
dimensionless backbone turns out not to depend on its parameters or the overlap (a
shape-invariant law, such as a Hertz written from scratch), a fast table built on load
(:mod:`models.tables.autotable`). A file that breaks the contract raises :class:`LawFileError`
naming the file and what is wrong.

A law file is Python code: loading it runs it, with the user's rights. Everything it
raises while it loads (an exception, ``sys.exit``, with any code) becomes one
:class:`LawFileError`; only an interrupt (Ctrl-C) goes through as one.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import inspect
import math
import numbers
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.models import registry
from beadrod.models.law import (
    SCENE_KEYS,
    YOUNG,
    ContactLaw,
    Param,
    Physics,
    Presentation,
    Prior,
    prior_median,
)
from beadrod.models.tables.autotable import attach_fast_backbone

__all__ = ["LawFileError", "load_law_file", "NAME_MAX"]

NAME_MAX = 64
"""Longest NAME: it becomes file names (laws/NAME.json, idata/NAME.nc) in any folder."""

# ASCII only (str.isidentifier would let in any Unicode letter); fullmatch: "$" alone
# would accept a trailing newline
_NAME = re.compile(rf"[A-Za-z][A-Za-z0-9_]{{0,{NAME_MAX - 1}}}")
_QUANTILES = (0.01, 0.5, 0.99)
# the amplitudes x = delta_a/delta0 loss_increment is checked at (x = 0: the limit of a
# small sweep; 2: the end of the fast backbone's range)
_LOSS_X = (0.0, 1e-6, 0.1, 0.5, 1.0, 2.0)
# the parameters (a, b) for which a models.law.Prior of each kind is proper
_PROPER = {"uniform": lambda a, b: a < b, "loguniform": lambda a, b: 0 < a < b,
           "lognormal": lambda a, b: a > 0 and b > 0, "normal": lambda a, b: b > 0,
           "halfnormal": lambda a, b: a > 0}


class LawFileError(ValueError):
    """A law file that breaks the contract (the message names the file)."""


def _fail(path: Path, what: str) -> LawFileError:
    return LawFileError(f"law file {path}: {what}")


def _raised(exc: BaseException, when: str) -> str:
    """What the user's code did ``when``, in words: an exit and its code, or the exception
    and the first line of its message."""
    if isinstance(exc, SystemExit):
        return f"called sys.exit({exc.code!r}) {when} (a law file defines a law; it must not exit)"
    try:
        lines = str(exc).strip().splitlines()
    except Exception:  # noqa: BLE001  (a user exception whose __str__ fails)
        lines = []
    return f"raised {type(exc).__name__} {when}" + (f": {lines[0]}" if lines else "")


def _module(path: Path):
    if not path.is_file():
        raise _fail(path, "no such file")
    spec = importlib.util.spec_from_file_location(f"beadrod_user_law_{path.stem}", path)
    if spec is None or spec.loader is None:
        raise _fail(path, "cannot be imported as Python")
    mod = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(mod)
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # noqa: BLE001  (the user's code, sys.exit too: report it)
        raise _fail(path, _raised(exc, "on import")) from exc
    return mod


def _check_prior(path: Path, name: str, prior: Any) -> None:
    """A proper scalar prior with a finite, increasing inverse CDF (module doc)."""
    where = f"PRIORS[{name!r}]"
    if isinstance(prior, Prior):
        proper = _PROPER.get(prior.kind)
        if proper is None:
            raise _fail(path, f"{where} = {prior!r}: kind must be one of {list(_PROPER)}")
        ab = (prior.a, prior.b)
        if not (all(isinstance(v, (int, float)) and math.isfinite(v) for v in ab)
                and proper(*ab)):
            raise _fail(path, f"{where} = {prior!r} is not a proper prior (uniform, "
                              "loguniform: a < b, loguniform a > 0; normal, lognormal: b > 0; "
                              "lognormal, halfnormal: a > 0)")
        return
    kind = type(prior).__name__
    if not (hasattr(prior, "log_prob") and hasattr(prior, "sample")):
        raise _fail(path, f"{where} is not a distribution (got {kind})")
    shape = (tuple(getattr(prior, "batch_shape", ())), tuple(getattr(prior, "event_shape", ())))
    if shape != ((), ()):
        raise _fail(path, f"{where} ({kind}) has batch shape {shape[0]} and event shape "
                          f"{shape[1]}: a prior is one scalar parameter's (both ())")
    try:
        qs = [float(prior.icdf(jnp.asarray(q))) for q in _QUANTILES]
    except NotImplementedError:
        raise _fail(path, f"{where} ({kind}) has no inverse CDF (icdf); every prior must be "
                          "a proper distribution that has one (e.g. Uniform, LogUniform, "
                          "Normal, LogNormal; not an improper prior such as ImproperUniform): "
                          "nested sampling and the prior tables map [0, 1] through it"
                    ) from None
    if not (all(math.isfinite(q) for q in qs) and qs[0] < qs[1] < qs[2]):
        raise _fail(path, f"{where} ({kind}) has no proper quantiles: icdf at {_QUANTILES} "
                          f"gives {qs} (finite and increasing expected)")
    if not math.isfinite(float(prior.log_prob(jnp.asarray(qs[1])))):
        raise _fail(path, f"{where} ({kind}) has no finite density at its median {qs[1]:.4g}")


def _check_name(path: Path, name: Any, reserved: Mapping[str, str]) -> str:
    """``name`` if it is a valid, free law name (refused in one line otherwise).

    Taken: every registered law's name (built-in, or from another file) and the
    ``reserved`` names, compared without case, since NAME names files and a folder on a
    case-insensitive file system holds one of hertz.nc and Hertz.nc."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        shown = repr(name)
        shown = "nothing" if name is None else shown if len(shown) <= 40 else shown[:36] + "..."
        raise _fail(path, f"NAME is missing or not a name: a letter, then letters, digits or _, "
                          f"at most {NAME_MAX} characters (e.g. NAME = \"my_law\"); got "
                          f"{shown}")
    mine = (str(path), str(path.resolve()))   # this very file, loaded before: not taken
    owners = {law.name.lower(): f"the law '{law.name}' ({law.source})" for law in registry.laws()
              if law.source not in mine}
    owners.update({k.lower(): f"{what} ('{k}')" for k, what in reserved.items()})
    if name.lower() in owners:
        raise _fail(path, f"NAME = {name!r} is taken by {owners[name.lower()]}; choose "
                          "another NAME")
    return name


def _optional(path: Path, mod: Any, key: str, kind: type, default: Any) -> Any:
    value = getattr(mod, key, default)
    if not isinstance(value, kind):
        raise _fail(path, f"{key} must be a {kind.__name__} (got {type(value).__name__})")
    return value


def load_law_file(path: str | Path, scene: dict[str, float], *,
                  reserved: Mapping[str, str] | None = None) -> ContactLaw:
    """The :class:`ContactLaw` that the file at ``path`` defines, checked against the
    contract at the scene quantities ``scene`` and the prior medians.

    ``reserved``: names no law may take besides the registered laws' (name -> what holds
    it, for the message; e.g. the law-free baseline's). Whatever the file's code raises
    while it loads becomes a :class:`LawFileError` naming the file."""
    path = Path(path)
    mod = _module(path)
    try:
        return _law_of(path, mod, scene, dict(reserved or {}))
    except (LawFileError, KeyboardInterrupt):
        raise
    except BaseException as exc:  # noqa: BLE001  (the file's functions run in the checks)
        raise _fail(path, _raised(exc, "while it was checked")) from exc


def _law_of(path: Path, mod: Any, scene: dict[str, float],
            reserved: dict[str, str]) -> ContactLaw:
    name = _check_name(path, getattr(mod, "NAME", None), reserved)
    label = _optional(path, mod, "LABEL", str, name)
    if not label.strip() or not label.isprintable():
        raise _fail(path, "LABEL must be one line of printable text")
    reference = _optional(path, mod, "REFERENCE", str, f"user law file {path.name}")
    description = _optional(path, mod, "DESCRIPTION", str, "")
    adhesive = _optional(path, mod, "ADHESIVE", bool, False)
    priors = getattr(mod, "PRIORS", None)
    if not isinstance(priors, dict):
        raise _fail(path, "PRIORS is missing (a dict from each law parameter to a prior)")
    force = getattr(mod, "force", None)
    if not callable(force):
        raise _fail(path, "force(delta, *, ...) is missing")
    keys = _keywords(path, force, "force", "the overlap delta [m]", priors)
    loss_exponent = _loss_exponent(path, mod)
    increment = getattr(mod, "loss_increment", None)
    if increment is not None and not callable(increment):
        raise _fail(path, f"loss_increment must be a function loss_increment(x, *, ...) "
                          f"(got {type(increment).__name__})")
    loss_keys = (_keywords(path, increment, "loss_increment", "the amplitude x = "
                           "delta_a/delta0", priors) if increment is not None else [])
    for k, pr in priors.items():
        if k in SCENE_KEYS and k != YOUNG.name:
            raise _fail(path, f"PRIORS[{k!r}] shadows a scene quantity: rename it")
        if k not in keys and k not in loss_keys:
            raise _fail(path, f"PRIORS[{k!r}] is not an argument of force or loss_increment")
        _check_prior(path, k, pr)

    # the law's functions get the resolved keywords (models.law, "Keyword conventions");
    # the file's, the ones they name
    def user_force(delta, **kw):
        return force(delta, **{k: kw[k] for k in keys})

    def user_loss(x, **kw):
        return increment(x, **{k: kw[k] for k in loss_keys})

    # a fitted E (the one scene quantity a file may fit) is the built-in laws' E with the
    # file's prior: its unit, label, scene value and physical bounds come from YOUNG
    law_params = tuple(
        dataclasses.replace(YOUNG, prior=pr, description="law-file parameter: Young's "
                            "modulus, with the file's prior") if k == YOUNG.name else
        Param(k, "?", k, pr, f"law-file parameter {k}") for k, pr in priors.items())
    law = ContactLaw(
        name=name, params=law_params,
        physics=Physics(force=user_force, loss_exponent=loss_exponent,
                        loss_increment=user_loss if increment is not None else None),
        presentation=Presentation(label=label, reference=reference, description=description),
        source=str(path))
    _check_force(path, law, scene, adhesive=adhesive)
    if increment is not None:
        _check_loss_increment(path, law, scene)
    return attach_fast_backbone(law, scene)


def _keywords(path: Path, fn: Any, what: str, first: str, priors: dict) -> list[str]:
    """The keyword arguments of the file's function ``fn`` (named ``what``): each a law
    parameter (a key of ``priors``) or a scene quantity, after one positional argument
    (``first``, in messages)."""
    try:
        params = list(inspect.signature(fn).parameters.values())
    except (TypeError, ValueError):
        raise _fail(path, f"{what} has no signature Python can read (write it with def)"
                    ) from None
    if not params or params[0].kind not in (params[0].POSITIONAL_ONLY,
                                            params[0].POSITIONAL_OR_KEYWORD):
        raise _fail(path, f"{what} must take {first} as its first argument")
    keys = [p.name for p in params[1:]]
    for k in keys:
        if k not in priors and k not in SCENE_KEYS:
            raise _fail(path, f"{what}'s argument {k!r} has no prior in PRIORS and is not a "
                              f"scene quantity ({', '.join(SCENE_KEYS)})")
    return keys


def _loss_exponent(path: Path, mod: Any) -> float | None:
    """The file's ``LOSS_EXPONENT`` as a float (None where it sets none)."""
    value = getattr(mod, "LOSS_EXPONENT", None)
    if value is None:
        return None
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if not (ok and math.isfinite(float(value)) and float(value) >= 0.0):
        raise _fail(path, f"LOSS_EXPONENT = {value!r}: it must be a finite real number >= 0 "
                          "(its linear loss scales as Omega^LOSS_EXPONENT; e.g. 3 for "
                          "Kuwabara-Kono); leave it out to have the background exponent fitted")
    return float(value)


def _medians(law: ContactLaw) -> dict[str, float]:
    return {p.name: prior_median(p.prior) for p in law.params}


def _run(path: Path, what: str, theta: dict[str, float], fn: Any) -> Any:
    """``fn()``, the file's function ``what`` run at the prior medians ``theta``: whatever
    it raises (sys.exit too) becomes a LawFileError; Ctrl-C goes through."""
    try:
        return fn()
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # noqa: BLE001  (the user's code, sys.exit too)
        raise _fail(path, f"{what} " + _raised(exc, f"at the prior medians {theta}")) from exc


def _check_force(path: Path, law: ContactLaw, scene: dict[str, float], *,
                 adhesive: bool) -> None:
    theta = _medians(law)
    kw = law.resolve(scene, theta)

    def probe():
        d0 = float(law.overlap(**kw))
        f0, k0 = (float(v) for v in jax.jvp(lambda d: law.physics.force(d, **kw),
                                            (jnp.asarray(d0),), (jnp.asarray(1.0),)))
        return d0, f0, k0, float(law.physics.force(jnp.asarray(-0.5 * d0), **kw))

    d0, f0, k0, f_neg = _run(path, "force", theta, probe)
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


def _check_loss_increment(path: Path, law: ContactLaw, scene: dict[str, float]) -> None:
    """The file's loss_increment at the prior medians: one finite value >= 0 at each
    amplitude of :data:`_LOSS_X`, finite gradients there in the law's parameters (through
    the resolved keywords, as the sampler takes them) and in x where x > 0."""
    theta = _medians(law)
    x = jnp.asarray(_LOSS_X)

    def at(xi, th):   # at one amplitude: each x's gradient on its own
        return jnp.reshape(law.physics.loss_increment(xi, **law.resolve(scene, th)), ())

    def probe():
        value = np.asarray(law.physics.loss_increment(x, **law.resolve(scene, theta)), float)
        if value.shape not in ((), x.shape):
            return value, None, None
        th = {k: jnp.asarray(v, float) for k, v in theta.items()}
        d_x, d_theta = jax.vmap(jax.grad(at, argnums=(0, 1)), in_axes=(0, None))(x, th)
        return value, {k: np.asarray(v, float) for k, v in d_theta.items()}, np.asarray(d_x)

    value, d_theta, d_x = _run(path, "loss_increment", theta, probe)
    where = f"at the prior medians {theta}"
    if d_theta is None:
        raise _fail(path, f"loss_increment(x) at x = {list(_LOSS_X)} returned shape "
                          f"{value.shape}: one value per amplitude expected")
    value = np.broadcast_to(value, x.shape)
    shown = ", ".join(f"{a:g}: {v:.4g}" for a, v in zip(_LOSS_X, value))
    if not np.all(np.isfinite(value)):
        raise _fail(path, f"NaN or infinite loss_increment {where} (x: value {shown})")
    if np.any(value < 0):
        raise _fail(path, f"negative loss_increment {where} (x: value {shown}); it is a loss "
                          "added to the linear one, Delta(1/Q) >= 0")
    if _LOSS_X[0] == 0.0 and abs(value[0]) > 1e-12:
        # a constant part would be a second linear loss, which the reference Q already
        # measures: the two could not be told apart
        raise _fail(path, f"loss_increment(0) = {value[0]:.4g} {where}: the increment must "
                          "vanish at zero amplitude (the linear loss is the reference Q's)")
    for k, g in d_theta.items():
        bad = [a for a, ok in zip(_LOSS_X, np.isfinite(g)) if not ok]
        if bad:
            raise _fail(path, f"loss_increment has a NaN or infinite gradient in {k} at x = "
                              f"{bad} {where} (at x = 0, write a power of x with a double "
                              "where: docs/adding-a-law.md)")
    bad = [a for a, ok in zip(_LOSS_X, np.isfinite(d_x)) if a > 0 and not ok]
    if bad:
        raise _fail(path, f"loss_increment has a NaN or infinite gradient in x at x = {bad} "
                          f"{where}")
