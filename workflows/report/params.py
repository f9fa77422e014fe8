"""The report's parameters: what each one means, its prior, its posterior and its checks.

:data:`PARAMETERS` is the glossary (symbol, meaning, the unit the report prints it in).
Posterior summaries arrive in SI units (``pipeline`` summaries: mean, sd, q05, q95);
they are printed in the glossary's unit, and ``delta0_ref_log``, sampled as the natural
log of an overlap in metres, is printed as the overlap in nm (its interval exactly, its
sd by the delta method, sd(e^u) ~ e^mean sd(u)).

The priors table renders each fitted parameter's prior (:func:`inference.model.priors.prior`)
with its justification: a law parameter's from its :class:`models.law.Param` description,
a nuisance parameter's from the docstring of :mod:`inference.model.priors`. The checks
(:func:`parameter_checks`, columns of the report's warnings table) are those a
statistician would raise on reading the tables: a posterior piled against a hard prior
bound (its 90 % interval ends within a tenth of its own width of the bound, so the bound,
not the data, cuts it off), filling its prior (the data do not constrain it), or spanning
most of its prior while leaning towards one bound (the data barely constrain it); and a
modulus outside the scene's expected range.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from beadrod.inference.model.variables import VARIABLES
from beadrod.workflows.report.tables import (
    DASH,
    fmt_num,
    fmt_pm,
    is_failed,
    law_label,
    pm_decimals,
    to_float,
)

__all__ = ["Param", "PARAMETERS", "GLOSSARY", "param_info", "display_stats", "prior_text",
           "prior_reasons", "priors_table", "glossary_table", "param_table", "ParamCheck",
           "parameter_checks", "parameter_warnings", "truth_tables", "BOUND_FRACTION",
           "WIDE_FRACTION"]

BOUND_FRACTION = 0.1
"""An interval end closer to a hard prior bound than this fraction of its width is piled
against the bound."""
WIDE_FRACTION = 0.5
"""A 90 % interval wider than this fraction of its prior's range (on the prior's own
scale, log for a log-uniform prior) is barely constrained by the data: near one bound it
leans towards it, rather than being piled against it (a flat posterior's 90 % interval
ends 0.056 of its width from each bound; a mild tilt moves one end away)."""


@dataclass(frozen=True)
class Param:
    """One parameter as the report prints it: ``value_shown = value_SI * scale`` (after
    exp() when ``log``: the site is the natural log of the SI quantity). ``meaning``
    defaults to the site's description in :data:`inference.model.variables.VARIABLES`."""

    symbol: str
    unit: str = "–"
    scale: float = 1.0
    log: bool = False
    logged: bool = False  # the site is a natural log and is printed as one
    meaning: str = ""


PARAMETERS: dict[str, Param] = {
    "young": Param("E", "GPa", 1e-9),
    "eta": Param("η", "MPa s", 1e-6),
    "eta_shift": Param("η_shift", "MPa s", 1e-6),
    "eta_q": Param("η_Q", "MPa s", 1e-6),
    "n": Param("n", meaning="exponent of the rough-contact law F = C δ^n (n = 3/2: Hertz)"),
    "gamma": Param("γ", "J/m²"),
    "delta0_ref_log": Param("δ0,ref", "nm", 1e9, log=True,
                            meaning="static overlap of the power law at the nominal mount "
                                    "(it replaces the unidentifiable prefactor C); sampled "
                                    "as ln(δ0,ref / 1 m), printed in nm"),
    "delta0_scatter": Param("s_δ0", meaning="protocol-to-protocol sd of ln δ0_p about "
                                            "ln δ0,ref (remounting the bead changes the "
                                            "contact's stiffness scale)"),
    "sigma_shift": Param("σ_shift", meaning="floor of the noise sd of the measured Δf/f0 "
                                            "of one drive sweep"),
    "kappa_shift": Param("κ_shift", meaning="part of the shift noise that grows with the "
                                            "shift, as a fraction of it (bent peaks, wear)"),
    "tau_shift": Param("τ_shift", meaning="sd of the offset all shifts of a protocol share "
                                          "through its first reference sweep"),
    "sigma_amp": Param("σ_amp", meaning="relative error of a drive sweep's resonance "
                                        "amplitude"),
    "tau_amp": Param("τ_amp", meaning="relative error of a protocol's reference amplitude, "
                                      "shared by its amplitude ratios"),
    "offset_amp_down": Param("o_amp", meaning="ln amplitude of down sweeps against up "
                                              "sweeps"),
    "loss_exponent": Param("β", meaning="exponent of the background loss L0 Ω^β (0: constant "
                                        "loss factor, 1: dashpot, 3: radiation into the rod)"),
    "loss_gain": Param("g_loss", meaning="baseline: change of ln L at the pivot amplitude"),
    "loss_power": Param("p_loss", meaning="baseline: exponent of its loss change in the "
                                          "amplitude scale"),
    "offset_down": Param("o_down", meaning="constant offset of Δf/f0 in down sweeps against "
                                           "up sweeps (the delayed jump of a softening "
                                           "resonance)"),
    "sigma_logq": Param("σ_lnQ"),
    "mu_logq": Param("μ_lnQ", logged=True,
                     meaning="mean of ln Q_p in the law-free Q model of the laws that "
                             "predict no Q (e^μ is the typical Q)"),
    "tau_logq": Param("τ_lnQ"),
    "a_ref": Param("a_ref"),
    "amp": Param("a", meaning="baseline: Δf/f0 = −a x_s^b with x_s = δ_a ω0²/g; a is its "
                              "value at x_s = 1"),
    "power": Param("b", meaning="baseline: the power b of that curve (0.5: square root, 4: "
                                "quartic)"),
    "mu_f0": Param("μ_f0", "Hz", meaning="baseline: mean linear resonance over protocols, "
                                         "f0_p ~ Normal(μ_f0, τ_f0)"),
    "tau_f0": Param("τ_f0", "Hz", meaning="baseline: sd of f0_p over protocols"),
}

GLOSSARY: dict[str, str] = {
    "law": "a contact law F(δ) with its parameters (Hertz, power law, viscoelastic, JKR); "
           "each is one NumPyro model of all the data",
    "baseline": "the law-free baseline: any smooth monotone softening curve −a x^b; a law "
                "that loses to it misses the data's shape",
    "rung": "how a law becomes a predicted shift Δf/f0(x), x = δ_a/δ0: 'first_order' (the "
            "paper's averaged tangent stiffness), 'paper_eq25' (the paper's Eq. 25, where η "
            "enters the shift), 'backbone' (the exact conservative backbone)",
    "backbone": "the amplitude-frequency curve of the undamped oscillator with contact "
                "loss: the exact shift of F ~ δ^n, which softens for every n > 1",
    "scene": "the experimental setup (bead, rod, materials, preload, drive) read from "
             "scene.toml; it sets the load, the mass and the expected modulus range",
    "protocol": "one mounting of the bead: a reference sweep (f0, Q) and drive sweeps up "
                "and down at rising amplitude",
}


_PRIOR_CLAUSE = re.compile(r"\s*Prior [A-Za-z]+\(.*?\)[^:.]*:\s*")


def law_param(name: str) -> Any | None:
    """The :class:`models.law.Param` of a registered law's parameter ``name`` (None for the
    nuisance parameters of inference.model.priors)."""
    from beadrod.models import registry

    for law in registry.laws():
        if name in law.param_names:
            return law.param(name)
    return None


def _split_description(text: str) -> tuple[str, str]:
    """A law parameter's description 'Meaning. Prior Dist(...) unit: why.' as (meaning,
    why)."""
    m = _PRIOR_CLAUSE.search(text)
    if m is None:
        return text.strip(), ""
    return text[:m.start()].strip().rstrip("."), text[m.end():].strip()


def param_info(name: str) -> Param:
    """The report's entry for ``name``, its meaning filled in from the law's parameter
    (models.law.Param) or inference.model.variables."""
    p = PARAMETERS.get(name, Param(name))
    if not p.meaning:
        lp = law_param(name)
        info = VARIABLES.get(name)
        meaning = (_split_description(lp.description)[0] if lp is not None
                   else info.description if info else "(no description)")
        p = replace(p, meaning=meaning)
    return p


def _shown(name: str, v: float) -> float:
    p = param_info(name)
    return (math.exp(v) if p.log else v) * p.scale


def display_stats(row: Mapping) -> dict[str, float]:
    """mean, sd, q05, q95 of a parameter summary in the printed unit."""
    name = str(row.get("name", "?"))
    p = param_info(name)
    mean, sd = to_float(row.get("mean")), to_float(row.get("sd"))
    out = {"q05": _shown(name, to_float(row.get("q05"))),
           "q95": _shown(name, to_float(row.get("q95")))}
    if p.log:
        out["mean"] = _shown(name, mean)
        out["sd"] = out["mean"] * sd
    else:
        out["mean"], out["sd"] = mean * p.scale, sd * p.scale
    return out


# ------------------------------------------------------------------------------ priors
def _g(v: float) -> str:
    return f"{v:.4g}"


_FAMILIES = ("LogUniform", "Uniform", "LogNormal", "HalfNormal", "Normal")
"""The distribution families written in their own notation; a subclass (a sampler
coordinate of its own: inference.model.coordinates.ScaledNormal, inference.model.priors.
LogUniformLogit) is the same prior and is written as its family."""


def _family(d: Any) -> str | None:
    return next((c.__name__ for c in type(d).__mro__ if c.__name__ in _FAMILIES), None)


def _args_text(d: Any) -> str:
    """A distribution's class and parameters as NumPyro names them, in SI units (any
    class: never its repr, whose object address changes from run to run)."""
    args = []
    for k in getattr(d, "arg_constraints", None) or {}:
        try:
            v = np.asarray(getattr(d, k), float)
        except (AttributeError, TypeError, ValueError):
            continue
        args.append(f"{k}={_g(float(v))}" if v.size == 1 else f"{k}=<{v.size} values>")
    base = getattr(d, "base_dist", None)  # a truncated or transformed distribution's
    of = "" if base is None else f" of {_args_text(base)}"
    return f"{type(d).__name__}({', '.join(args)}){of}"


def prior_text(name: str, d: Any) -> str:
    """A numpyro distribution in words and the printed unit, e.g. 'Uniform(150, 250) GPa';
    a family other than :data:`_FAMILIES` as its class and parameters in SI units."""
    p = param_info(name)
    unit = "" if p.unit == "–" else f" {p.unit}"
    kind = _family(d)
    low, high = getattr(d, "low", None), getattr(d, "high", None)
    loc, scale = getattr(d, "loc", None), getattr(d, "scale", None)
    if kind in ("Uniform", "LogUniform") and low is not None and high is not None:
        return f"{kind}({_g(float(low) * p.scale)}, {_g(float(high) * p.scale)}){unit}"
    if kind == "Normal" and p.logged:
        return f"Normal(ln {_g(math.exp(float(loc)))}, {_g(float(scale))})"
    if kind == "Normal" and p.log:
        return (f"ln {p.symbol} ~ Normal(ln {_g(math.exp(float(loc)) * p.scale)}{unit}, "
                f"{_g(float(scale))})")
    if kind == "LogNormal" and loc is not None:
        return f"LogNormal(ln {_g(math.exp(float(loc)))}, {_g(float(scale))}){unit}"
    if kind == "Normal":
        return f"Normal({_g(float(loc) * p.scale)}, {_g(float(scale) * p.scale)}){unit}"
    if kind == "HalfNormal":
        return f"HalfNormal({_g(float(scale) * p.scale)}){unit}"
    si = unit if p.scale == 1.0 and not p.log else " (SI units)"
    return _args_text(d) + si


def _plain(text: str) -> str:
    """reStructuredText markup of a docstring as plain text."""
    text = re.sub(r":\w+:`~?([^`]+)`", r"\1", text)
    return re.sub(r"``([^`]+)``", r"\1", " ".join(text.split()))


_DIST = re.compile(r"^(Normal|Uniform|LogNormal|HalfNormal|LogUniform)\([^)]*\)[^:]*:\s*")


def prior_reasons(doc: str) -> dict[str, str]:
    """Parameter -> the justification of its prior, from a docstring of bullets
    '- ``name`` ~ Dist(...): why' (several names may share a bullet)."""
    out: dict[str, str] = {}
    for bullet in re.split(r"\n\s*- ", "\n" + doc)[1:]:
        head, _, why = bullet.partition(": ")
        names = re.findall(r"``(\w+)``", head)
        why = _DIST.sub("", _plain(why).strip())
        # the first two sentences carry the physics; later ones, the sampler's coordinates
        why = " ".join(re.split(r"(?<=\.) (?=[A-Z])", why)[:2])
        for n in names:
            out.setdefault(n, why)
    return out


def priors_table(laws: Sequence[Mapping]) -> tuple[list[str], list[list[str]], list[bool]]:
    """Every prior of every fitted law: parameter, distribution, laws, why."""
    from beadrod.inference.model import priors

    reasons = prior_reasons(priors.__doc__ or "")
    used: dict[str, list[str]] = {}
    dists: dict[str, Any] = {}
    for lw in laws:
        for p in lw.get("params") or []:
            name = p.get("name")
            try:
                dists.setdefault(name, priors.prior(name))
            except KeyError:  # a derived quantity, not a sampled parameter
                continue
            used.setdefault(name, []).append(law_label(lw))
    body = []
    for name in used:
        lp = law_param(name)
        why = _split_description(lp.description)[1] if lp is not None else reasons.get(name)
        body.append([f"{param_info(name).symbol} ({name})", prior_text(name, dists[name]),
                     ", ".join(used[name]), why or DASH])
    return ["parameter", "prior", "laws", "why this prior"], body, [False] * len(body)


def glossary_table(laws: Sequence[Mapping]) -> tuple[list[str], list[list[str]], list[bool]]:
    """The parameters of the fitted laws: symbol, site name, meaning, printed unit."""
    names: list[str] = []
    for lw in laws:
        names += [p["name"] for p in lw.get("params") or [] if p.get("name") not in names]
    body = [[param_info(n).symbol, n, param_info(n).meaning, param_info(n).unit] for n in names]
    return ["symbol", "name", "meaning", "unit"], body, [False] * len(body)


# --------------------------------------------------------------------------- posterior
def _fixed_pair(a: float, b: float, sd: float) -> tuple[str, str]:
    """Interval ends with the sd's decimals; with three significant digits each when the
    interval spans more than a decade (a log-uniform posterior)."""
    if a > 0 and b > 10 * a:
        return f"{a:.3g}", f"{b:.3g}"
    if math.isfinite(sd) and sd > 0:
        d = max(pm_decimals(sd), 0)
        return f"{a:.{d}f}", f"{b:.{d}f}"
    return fmt_num(a), fmt_num(b)


def _mean_sd(s: Mapping[str, float]) -> str:
        return fmt_pm(s["mean"], s["sd"])


def truth_value(name: str, truth: Mapping | None) -> float | None:
    """The world's truth of ``name`` in the printed unit (None if it defines none)."""
    v = ((truth or {}).get("values") or {}).get(name)
    return None if v is None else _shown(name, float(v["value"]))


def param_table(law: Mapping, truth: Mapping | None
                ) -> tuple[list[str], list[list[str]], list[bool]]:
    """Posterior of a law's global parameters in printed units, with the world's truth
    where it defines one ('none' where it does not: the Truth section says why)."""
    params = list(law.get("params") or [])
    show_truth = truth is not None and any(truth_value(p.get("name"), truth) is not None
                                           for p in params)
    headers = ["parameter", "unit", "mean ± sd", "90 % interval"]
    if show_truth:
        headers += ["truth", "truth in 90 %"]
    body = []
    for p in params:
        name = str(p.get("name", "?"))
        s = display_stats(p)
        lo, hi = _fixed_pair(s["q05"], s["q95"], s["sd"])
        cells = [f"{param_info(name).symbol} ({name})", param_info(name).unit, _mean_sd(s),
                 DASH if lo == DASH else f"[{lo}, {hi}]"]
        if show_truth:
            t = truth_value(name, truth)
            if t is None:
                cells += ["none", DASH]
            else:
                inside = s["q05"] <= t <= s["q95"]
                cells += [f"{t:.4g}", "yes" if inside else "**no**"]
        body.append(cells)
    return headers, body, [is_failed(law)] * len(body)


# ------------------------------------------------------------------------------ checks
def _bounds(name: str) -> tuple[float, float, bool] | None:
    """Hard (finite, both-sided) prior bounds of ``name`` [SI] and whether they are on a
    log scale; None for priors with an unbounded side."""
    from beadrod.inference.model.priors import prior

    try:
        d = prior(name)
    except KeyError:
        return None
    low, high = getattr(d, "low", None), getattr(d, "high", None)
    if low is None or high is None:
        return None
    return float(low), float(high), "LogUniform" in type(d).__name__


@dataclass(frozen=True)
class ParamCheck:
    """One finding of :func:`parameter_checks`. ``check``: "prior" (a posterior against a
    hard prior bound; only warnings are listed) or "range" (E against the scene's expected
    range, inside or not); ``symbol`` and ``interval`` (the 90 % interval in the printed
    unit, '[212, 236] GPa'): what the warnings table shows, with ``cell``, the finding in a
    few words; ``sentence``: the finding in full."""

    check: str
    warns: bool
    symbol: str
    interval: str
    cell: str
    sentence: str


def _prior_verdict(name: str, p: Mapping, unit: str) -> tuple[str, str, str] | None:
    """(cell, clause, why) of a posterior against a hard prior bound, None if it is not."""
    b = _bounds(name)
    if b is None:
        return None
    lo_b, hi_b, log = b
    q05, q95 = to_float(p.get("q05")), to_float(p.get("q95"))
    f = math.log if log else float
    width = f(q95) - f(q05)
    near_lo = f(q05) - f(lo_b) < BOUND_FRACTION * width
    near_hi = f(hi_b) - f(q95) < BOUND_FRACTION * width
    share = width / (f(hi_b) - f(lo_b))   # of the prior's range, on its scale
    bounds = f"[{_g(_shown(name, lo_b))}, {_g(_shown(name, hi_b))}]"
    which = _g(_shown(name, lo_b if near_lo else hi_b))
    if near_lo and near_hi:
        return (f"fills its prior {bounds}", f"fills its prior {bounds}{unit}",
                "the data do not constrain it, and the evidence depends on the prior's width")
    if (near_lo or near_hi) and share > WIDE_FRACTION:
        scale = " on a log scale" if log else ""
        return (f"spans {share:.0%} of its prior {bounds}{scale}, leaning towards {which}",
                f"spans {share:.0%} of its prior {bounds}{unit}{scale}",
                f"the data barely constrain it and lean towards its bound {which}{unit}, "
                "which cuts the posterior off; the evidence depends on the prior's width")
    if near_lo or near_hi:
        return (f"piled against its bound {which}",
                f"is piled against its prior bound {which}{unit}",
                "the bound, not the data, cuts the posterior off (the law wants to go beyond "
                "its physical range)")
    return None


def parameter_checks(law: Mapping, young_range: Sequence[float] | None) -> list[ParamCheck]:
    """The prior-bound and physical-range checks of one law's posterior summaries."""
    out: list[ParamCheck] = []
    for p in law.get("params") or []:
        name = str(p.get("name"))
        info = param_info(name)
        unit = "" if info.unit == "–" else f" {info.unit}"
        s = display_stats(p)
        lo_s, hi_s = _fixed_pair(s["q05"], s["q95"], s["sd"])
        interval = f"[{lo_s}, {hi_s}]{unit}"
        desc = f"{info.symbol} = {_mean_sd(s)}{unit}, 90 % interval [{lo_s}, {hi_s}]"
        verdict = _prior_verdict(name, p, unit)
        if verdict is not None:
            cell, clause, why = verdict
            out.append(ParamCheck("prior", True, info.symbol, interval, cell,
                                  f"{desc}, {clause}: {why}."))
        q05, q95 = to_float(p.get("q05")), to_float(p.get("q95"))
        if (name == "young" and young_range is not None and len(young_range) == 2
                and math.isfinite(q05) and math.isfinite(q95)):
            r_lo, r_hi = (float(v) for v in young_range)
            outside = q05 > r_hi or q95 < r_lo
            where = "outside" if outside else "inside"
            out.append(ParamCheck(
                "range", outside, info.symbol, interval, where,
                f"{desc}, lies {where} the scene's expected range {_g(r_lo * info.scale)}-"
                f"{_g(r_hi * info.scale)}{unit}"
                + (": the law needs an unphysical modulus to fit." if outside else ".")))
    return out


def parameter_warnings(law: Mapping, young_range: Sequence[float] | None) -> list[str]:
    """Bound and physical-range warnings of one law's posterior summaries, one sentence
    each (the warnings among :func:`parameter_checks`)."""
    label = law_label(law)
    return [f"{label}: {c.sentence}" for c in parameter_checks(law, young_range) if c.warns]


# ------------------------------------------------------------------------------- truth
def truth_tables(truth: Mapping, laws: Sequence[Mapping]
                 ) -> tuple[tuple[list[str], list[list[str]], list[bool]], list[str]]:
    """(table of the truths of the fitted parameters, one line per fitted parameter the
    world defines no truth for, saying why)."""
    fitted: list[str] = []
    for lw in laws:
        fitted += [p["name"] for p in lw.get("params") or [] if p.get("name") not in fitted]
    values = truth.get("values") or {}
    body = [[f"{param_info(n).symbol} ({n})", f"{truth_value(n, truth):.4g}", param_info(n).unit,
             str(values[n].get("note", ""))] for n in fitted if n in values]
    none = truth.get("none") or {}
    lines = [f"{param_info(n).symbol} ({n}): "
             + str(none.get(n, f"no truth: world {truth.get('world', '?')!r} does not "
                               "define it")).removeprefix("no truth: ")
             for n in fitted if n not in values]
    return (["parameter", "truth", "unit", "what it is"], body, [False] * len(body)), lines
