"""``beadrod shift``: the predicted Delta f/f0 of a contact law at given amplitudes.

Every number printed is inside the domain where it means something, or refused with the
reason (exit status 2):

* x = delta_a/delta0 must be finite and 0 <= x <= X_MAX = 2. Past contact loss (x = 1 for
  Hertz) the bead flies free for part of the cycle; the first-order average of the
  tangent stiffness then no longer describes the motion, and far beyond it (x = 10 it
  predicts a stiffening, where the exact backbone softens) it means nothing. The laws'
  fast backbone paths are tabulated on the same range (models.tables.powerlaw_backbone).
* every law parameter must be finite and a value of that law's parameter
  (models.law.Param.problem): inside its domain (the power-law exponent 1 < n <= 3: n = 1
  is a linear spring, no shift, and past 3 no rough-contact model, and no table, applies;
  Maugis-Dugdale's lam in [0.1, 100], where its state is tabulated) and inside the
  physical bounds of its quantity (Young's modulus, viscosities and surface energies:
  models.scene.BOUNDS). The law's parameter says which; nothing here lists them.

* a scene quantity set by hand (``--param radius=...``) is held to the rules of
  ``scene.toml`` (models.nominal.check_scene_values: the scene's own bounds); a name that
  is neither a parameter of the law nor a scene quantity the law takes
  (models.nominal.scene_names) is refused with the names it takes.

Every input is used or refused: ``--scene`` with ``--builtin``, a shorthand flag for a
law without such a parameter (:data:`FLAGS`), two values for one name, and a scene
quantity whose every use is overridden are refused, as ``--n`` for a law without an
exponent always was.

The parameter checks are small functions (:func:`check_x`, :func:`check_param`) so that
any way of passing a parameter goes through the same check.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from beadrod.models.rungs import RUNGS
from beadrod.workflows import lawfiles

__all__ = ["register", "shift_table", "check_x", "check_param", "check_method", "X_MAX",
           "METHODS", "scene_keywords", "parse_params", "given_values", "FLAGS",
           "resolve_scene"]

X_MAX = 2.0
"""Largest x = delta_a/delta0 computed (models.tables.powerlaw_backbone.X_MAX: the tables
end there)."""

# --method takes every rung (models.rungs.RUNGS, spelled as everywhere else); a law
# computes those it lists in its ``rungs`` (check_method)
# as everywhere else
METHODS = tuple(RUNGS)

FLAGS: dict[str, str] = {"n": "n", "young": "young", "eta": "viscosity"}
"""Shorthand flag -> the quantity it sets: every parameter of the law of the flag's name
or whose nominal value is that scene quantity (``--eta``: each viscosity of the law),
else that scene quantity where the law takes it (models.nominal.scene_names); a law
with none of these refuses the flag."""



def _fmt(v: float) -> str:
    return f"{float(v):g}"


def check_x(xs: Sequence[float]) -> list[float]:
    """The amplitudes as floats, each finite with 0 <= x <= X_MAX; ValueError otherwise."""
    out = []
    for x in xs:
        x = float(x)
        if not math.isfinite(x):
            raise ValueError(f"--x {x}: an amplitude must be a finite number")
        if x < 0:
            raise ValueError(f"--x {_fmt(x)}: x = delta_a/delta0 is an amplitude ratio, >= 0")
        if x > X_MAX:
            raise ValueError(
                f"--x {_fmt(x)}: x must be <= {X_MAX:g}. Past contact loss (x = 1 for Hertz) "
                "the bead flies free for part of each cycle and the first-order average of "
                "the stiffness stops describing the motion (far past it, it even predicts a "
                "stiffening where the exact backbone softens): use --method backbone there; "
                f"its tables, like this command, end at x = {X_MAX:g}")
        out.append(x)
    return out


def check_param(law: Any, name: str, value: float) -> float:
    """``value`` as a float if it is finite and, for a parameter of ``law``, inside its
    domain and its quantity's physical bounds (models.law.Param.problem: the law's
    parameter says what its values are, not a list here); ValueError otherwise."""
    v = float(value)
    if name in law.param_names:
        problem = law.param(name).problem(v)
        if problem is not None:
            raise ValueError(f"law '{law.name}': {problem}")
    elif not math.isfinite(v):
        raise ValueError(f"{name} = {value}: must be a finite number")
    return v


def check_method(law: Any, method: str) -> str:
    """The law's rung for ``method``; ValueError if the law has no such rung."""
    from beadrod.models.rungs import check_rung

    rung = check_rung(method)
    if rung not in law.physics.rungs:
        raise ValueError(f"law '{law.name}' has no {method} rung; its rungs: "
                         f"{', '.join(law.physics.rungs)}")
    return rung


def scene_keywords(scene: Any) -> dict[str, float]:
    """The scene quantities a law's nominal parameters may come from, by name
    (inference.model.likelihood.scene_quantities, plus ``viscosity`` [Pa s] where the scene
    gives one)."""
    from beadrod.inference.model.likelihood import scene_quantities

    out = scene_quantities(scene)
    if scene.viscosity is not None:
        out["viscosity"] = float(scene.viscosity)
    return out


def parse_params(items: Sequence[str] | None) -> dict[str, float]:
    """``KEY=VALUE`` strings as a dict of floats; ValueError naming a malformed item or a
    key given twice with different values."""
    out: dict[str, float] = {}
    for item in items or []:
        key, sep, val = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ValueError(f"--param {item!r}: write KEY=VALUE, e.g. --param young=2e11")
        try:
            v = float(val)
        except ValueError:
            raise ValueError(f"--param {item!r}: {val!r} is not a number") from None
        if key in out and not _same(out[key], v):
            raise ValueError(f"--param {key}={_fmt(out[key])} and --param {key}={_fmt(v)} "
                             "contradict each other: give one value")
        out[key] = v
    return out


def _same(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))


def given_values(law: Any, params: dict[str, float],
                 flags: dict[str, float | None]) -> tuple[dict[str, float], dict[str, float]]:
    """(law parameters, scene quantities) set by ``params`` (``--param`` by name) and the
    shorthand ``flags`` (:data:`FLAGS`, None: not given), unchecked; ValueError for a
    flag the law has no use for, a name it does not take (naming those it takes), two
    values for one name, or a scene quantity whose every use is overridden."""
    from beadrod.models.law import SCENE_KEYS
    from beadrod.models.nominal import scene_names

    takes = scene_names(law)
    source = {k: f"--param {k}={_fmt(v)}" for k, v in params.items()}
    given = dict(params)

    def names() -> str:
        return (f"its parameters: {', '.join(law.param_names)}; the scene quantities it "
                f"takes: {', '.join(takes)}")

    for flag, v in flags.items():
        if v is None:
            continue
        quantity = FLAGS[flag]
        targets = [p.name for p in law.params if p.name == flag or p.scene_key == quantity]
        if not targets and quantity in takes:
            targets = [quantity]
        if not targets:
            raise ValueError(f"--{flag}: law '{law.name}' has no parameter --{flag} sets "
                             f"({quantity}); {names()}")
        for name in targets:
            if name in given and not _same(given[name], v):
                raise ValueError(f"--{flag} {_fmt(v)} and {source[name]} both set {name}: "
                                 "give one value")
            given[name], source[name] = v, f"--{flag} {_fmt(v)}"
    unknown = [k for k in given if k not in law.param_names and k not in takes]
    if unknown:
        derived = [k for k in unknown if k in SCENE_KEYS]
        why = (f" ({', '.join(derived)}: computed from the other scene quantities, not set "
               "by hand)" if derived else "")
        raise ValueError(f"law '{law.name}' takes no {', '.join(unknown)}{why}; {names()}")
    theta = {k: v for k, v in given.items() if k in law.param_names}
    scene = {k: v for k, v in given.items() if k not in law.param_names}
    for k in scene:
        fed = [p.name for p in law.params if p.scene_key == k]
        if k not in SCENE_KEYS and fed and all(p in theta for p in fed):
            raise ValueError(f"{source[k]} is not used: law '{law.name}' takes {k} only as "
                             f"the value of {', '.join(fed)}, given as well")
    return theta, scene


def resolve_scene(path: Path | str | None, builtin: str | None, *,
                  flag: str = "a scene file"):
    """(scene, source) named by a file or a built-in name (default: the paper's); both
    given is refused (``flag``: how the command names the file)."""
    from beadrod.models.scene import builtin_scene, load_scene

    if path is not None and builtin is not None:
        raise ValueError(f"give either {flag} or --builtin, not both")
    if path is not None:
        return load_scene(path), str(path)
    name = builtin or "paper"
    return builtin_scene(name), f"builtin:{name}"


def shift_table(law: str, x: list[float], *, method: str, n: float | None,
                scene_path: str | None, builtin: str | None, young: float | None,
                eta: float | None, params: dict[str, float] | None = None,
                law_files: list[str] | None = None) -> dict:
    """Delta f/f0 at each x for ``law`` (SI units in keys).

    ``n``, ``young`` and ``eta`` are shorthand flags (:data:`FLAGS`); ``params`` any law
    parameter or scene quantity by name (``beadrod laws`` lists them; :func:`given_values`).
    ``builtin`` (default: the paper's scene) and ``scene_path`` exclude each other. A law
    parameter not given takes the scene's value where the scene has one, else its prior
    median; ``sources`` says which. Every value is checked (:func:`check_x`,
    :func:`check_param`, models.nominal.check_scene_values); a refusal is a
    workflows.runtime.UserError. ``beadrod shift`` prints this; ``beadrod.shift``
    (workflows.api) returns it as a DataFrame."""
    from beadrod.workflows.runtime import UserError

    try:
        return _shift_table(law, x, method=method, n=n, scene_path=scene_path,
                            builtin=builtin, young=young, eta=eta, params=params,
                            law_files=law_files)
    except ValueError as exc:  # a law/method/parameter combination that does not exist
        raise UserError(str(exc)) from None


def _shift_table(law: str, x: list[float], *, method: str, n: float | None,
                 scene_path: str | None, builtin: str | None, young: float | None,
                 eta: float | None, params: dict[str, float] | None,
                 law_files: list[str] | None) -> dict:
    import numpy as np

    from beadrod.models.nominal import check_scene_values, checked_parameters, linear_state
    from beadrod.models.registry import get_law

    scene = resolve_scene(scene_path, builtin, flag="--scene")[0]
    lawfiles.load(law_files or [], scene)
    xs = check_x(x)
    contact = get_law(law)
    given, scene_given = given_values(contact, dict(params or {}),
                                      {"n": n, "young": young, "eta": eta})
    given = {k: check_param(contact, k, v) for k, v in given.items()}
    check_scene_values(scene, scene_given)
    rung = check_method(contact, method)
    sc = scene_keywords(scene)
    sc.update(scene_given)
    theta, sources = checked_parameters(contact, sc, given)
    state = linear_state(contact, sc, theta)
    kw, d0 = state["kw"], state["delta0_m"]
    xa = np.asarray(xs, float)
    try:
        # outside its domain (a table's range) a fast path holds a value that is not the
        # law's: the law computes those points by the generic quadrature (exact, slow)
        values, outside = contact.shift_everywhere(xa, rung=rung, **kw)
    except RuntimeError as exc:  # a forced-response solve that did not converge
        raise ValueError(f"law '{law}' ({rung}): {exc}") from None
    bad = [xv for xv, v in zip(xs, np.atleast_1d(values)) if not np.isfinite(v)]
    if bad:  # a defect, not an input error: say where instead of printing NaN
        raise ValueError(f"law '{law}' ({rung}) gives no finite shift at x = "
                         f"{', '.join(map(_fmt, bad))}")
    out = {"law": law, "method": rung, "rung": rung, "scene": scene.name, "x": xs,
           "delta_f_over_f0": [float(v) for v in np.atleast_1d(values)],
           "params": {k: float(v) for k, v in theta.items()}, "sources": sources,
           "delta0_m": float(d0), "f0_Hz": state["f0_Hz"],
           "generic_at_x": [float(v) for v in xa[outside]]}
    if "n" in theta:
        out["n"] = theta["n"]
    return out


def _run(args: argparse.Namespace) -> int:
    from beadrod.workflows.runtime import UserError

    try:
        params = parse_params(args.param)
    except ValueError as exc:
        raise UserError(str(exc)) from None
    table = shift_table(args.law, args.x, method=args.method, n=args.n,
                        scene_path=args.scene, builtin=args.builtin, young=args.young,
                        eta=args.eta, params=params, law_files=lawfiles.paths_of(args))
    if args.json:
        print(json.dumps(table, indent=2, allow_nan=False))
        return 0
    print(f"law {table['law']}, rung {table['rung']}, scene {table['scene']}")
    for k, v in table["params"].items():
        print(f"  {k} = {v:.6g} ({table['sources'][k]})")
    if table["generic_at_x"]:
        print("  outside the fast path's table at x = "
              + ", ".join(map(_fmt, table["generic_at_x"]))
              + ": computed there by the generic quadrature")
    print(f"{'x = delta_a/delta0':>20}  {'Delta f/f0':>14}")
    for xv, v in zip(table["x"], table["delta_f_over_f0"]):
        print(f"{xv:>20.6g}  {v:>14.8f}")
    return 0


def register(sub) -> None:
    # no models import here: building the parser must not start JAX
    p = sub.add_parser("shift", help="predicted resonance shift Delta f/f0 of a contact law",
                       description="Delta f/f0 at normalised amplitudes x = delta_a/delta0 "
                       "(0 <= x <= 2) for one contact law, at any rung the law has (--method: "
                       "series, first order, exact backbone, harmonic balance, time "
                       "integration, the paper's formulas). x > 1 means the contact opens "
                       "during the cycle (Hertz).")
    p.add_argument("--law", required=True,
                   help="contact law, e.g. hertz, powerlaw, viscoelastic, jkr, dmt (a wrong "
                   "name lists them all)")
    p.add_argument("--x", required=True, type=float, nargs="+",
                   help=f"amplitudes delta_a/delta0, each in [0, {X_MAX:g}]")
    p.add_argument("--n", type=float, help="power-law exponent, 1 < n <= 3 (law powerlaw)")
    p.add_argument("--method", default="first_order", choices=list(METHODS),
                   help="the rung: series (small-amplitude x^2 term), first_order (the "
                   "paper's averaged stiffness), backbone (exact, conservative), "
                   "harmonic_balance or time_integration (the forced, damped resonance peak "
                   "at Q = the law's linear Q, else 50; seconds per point), or paper_eq25 "
                   "(the paper's formulas), as far as the law has it (default: %(default)s)")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="a law parameter or scene quantity by the name `beadrod laws` gives, "
                   "e.g. --param gamma=0.5 (repeatable); a law parameter not given takes the "
                   "scene's value where it has one, else its prior median")
    lawfiles.add_argument(p)
    p.add_argument("--scene", help="scene TOML (default: the built-in scene)")
    p.add_argument("--builtin", help="built-in scene name instead of --scene (default: "
                   "paper)")
    p.add_argument("--young", type=float, help="Young's modulus [Pa] overriding the scene's")
    p.add_argument("--eta", type=float, help="viscosity [Pa s] >= 0, every viscosity of a "
                   "viscoelastic law (default: the scene's)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_run)
