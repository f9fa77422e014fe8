"""One colour, one label and one line style per model, for every figure.

Colours come from the law registry where a law gives one (``models.registry``, a law's
``color``), otherwise from :data:`PALETTE` (Okabe & Ito 2008, then Tol's "muted"
scheme: both colour-blind safe), in the order of the comparison's models
(``workflows.pipeline.fits.MODEL_SPECS``): each takes the free palette colour farthest, in
CIELAB, from those in use. A name seen for the first time later (a law a user
registers, a figure-only curve) takes the next such colour, so two models never share
one. Black is never a model's colour: black is the data.

Labels come from the registry's ``label``, else ``workflows.pipeline.fits.LABELS``, else the
name. :func:`tex` renders Greek words as symbols (``eta_shift`` -> ``$\\eta_\\mathrm{shift}$``)
for matplotlib's mathtext; :func:`param_label` gives a parameter's symbol (the
registry's ``Param.label`` where it has one).
"""

from __future__ import annotations

import colorsys
import re
from collections.abc import Iterable
from typing import Any

__all__ = [
    "PALETTE",
    "DATA_COLOR",
    "DIRECTION_STYLES",
    "DIRECTION_NAMES",
    "RUNG_LINESTYLES",
    "TENSION_STYLES",
    "model_names",
    "resolve",
    "color",
    "colors",
    "label",
    "tex",
    "param_label",
    "axis_label",
]

PALETTE: tuple[str, ...] = (
    # Okabe-Ito without black (the data) and yellow (unreadable on white)
    "#0072B2", "#E69F00", "#009E73", "#56B4E9", "#D55E00", "#CC79A7",
    # Tol "muted", pale sand last
    "#882255", "#44AA99", "#999933", "#332288", "#AA4499", "#117733", "#88CCEE", "#DDCC77",
)
"""Model colours, in the order they are handed out."""

DATA_COLOR = "#000000"
"""Measured points are black in every figure; no model is."""

# Up sweeps: filled triangles pointing up; down sweeps: open triangles pointing down.
# Direction 0 = up, 1 = down, as in data.process.ProcessedDataset.drive_direction.
DIRECTION_STYLES: dict[int, dict[str, Any]] = {
    0: {"marker": "^", "facecolor": DATA_COLOR, "edgecolor": DATA_COLOR, "ls": "-"},
    1: {"marker": "v", "facecolor": "white", "edgecolor": "#444444", "ls": "--"},
}
DIRECTION_NAMES: dict[int, str] = {0: "up sweep", 1: "down sweep"}

RUNG_LINESTYLES: dict[str, str] = {"backbone": "-", "first_order": "--", "paper_eq25": ":",
                                   "series": "-."}
"""Line style per rung: colour names the law, the dash names the forward model."""

TENSION_STYLES: dict[str, dict[str, Any]] = {
    # Tol high-contrast: the estimates of eta are not models, so not model colours
    "shift": {"color": "#004488", "ls": "-", "lw": 1.6, "fill": False},
    "q": {"color": "#DDAA33", "ls": "-", "lw": 2.4, "fill": True},
    "joint": {"color": "#BB5566", "ls": "--", "lw": 1.8, "fill": False},
}
"""Viscosity from the shift alone, from Q alone, and jointly (``fig_eta_tension``)."""

_ASSIGNED: dict[str, str] = {}


def _registry_laws() -> list[Any]:
    try:
        from beadrod.models import registry
    except ImportError:
        return []
    return list(registry.laws())


def _registry_law(name: str) -> Any | None:
    return next((law for law in _registry_laws() if getattr(law, "name", None) == name), None)


def _pipeline_labels() -> dict[str, str]:
    try:
        from beadrod.workflows.pipeline import fits
    except ImportError:
        return {}
    return dict(getattr(fits, "LABELS", {}))


def model_names() -> list[str]:
    """The comparison's models in their fixed order (``pipeline.MODEL_SPECS``), then any
    other registered law."""
    try:
        from beadrod.workflows.pipeline import fits

        names = list(getattr(fits, "MODEL_SPECS", {}))
    except ImportError:
        names = []
    for law in _registry_laws():
        n = getattr(law, "name", None)
        if n and n not in names:
            names.append(n)
    return names


def _is_black(c: str) -> bool:
    return c.lower() in ("#000", "#000000", "k", "black")


def _lab(c: str) -> tuple[float, float, float]:
    """CIELAB (D65) of a hex colour: distances there follow perceived differences."""
    rgb = [int(c.lstrip("#")[i:i + 2], 16) / 255.0 for i in (0, 2, 4)]
    lin = [v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4 for v in rgb]
    m = ((0.4124, 0.3576, 0.1805), (0.2126, 0.7152, 0.0722), (0.0193, 0.1192, 0.9505))
    xyz = [sum(a * b for a, b in zip(row, lin)) / w
           for row, w in zip(m, (0.95047, 1.0, 1.08883))]
    f = [t ** (1 / 3) if t > 0.008856 else 7.787 * t + 16 / 116 for t in xyz]
    return 116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])


def _distance(a: str, b: str) -> float:
    return sum((u - v) ** 2 for u, v in zip(_lab(a), _lab(b))) ** 0.5


def _spare_color(taken: Iterable[str]) -> str:
    """The unused palette colour farthest (CIELAB) from every colour in use and from
    the data's black, so that a new model never looks like an old one."""
    used = [c.lower() for c in taken]
    free = [c for c in PALETTE if c.lower() not in used]
    if free:
        ref = [*used, DATA_COLOR]
        return max(free, key=lambda c: min(_distance(c, u) for u in ref))
    # past the palette: golden-ratio hues at fixed lightness, never grey or black
    k = len(used)
    while True:
        r, g, b = colorsys.hls_to_rgb((0.61803398875 * k) % 1.0, 0.45, 0.75)
        c = f"#{int(255 * r):02x}{int(255 * g):02x}{int(255 * b):02x}"
        if c not in used:
            return c
        k += 1


def _registry_color(name: str) -> str | None:
    law = _registry_law(name)
    want = law.presentation.color if law is not None else None
    if isinstance(want, str) and want.startswith("#") and not _is_black(want):
        return want
    return None


def _assign(name: str) -> str:
    want = _registry_color(name)
    taken = {c.lower() for c in _ASSIGNED.values()}
    _ASSIGNED[name] = (want if want is not None and want.lower() not in taken
                       else _spare_color(_ASSIGNED.values()))
    return _ASSIGNED[name]


def _ensure_known() -> None:
    # every colour a law asks for first, then the others in the fixed order: a name's
    # colour does not depend on which figure asked first
    if not _ASSIGNED:
        names = model_names()
        for n in names:
            want = _registry_color(n)
            if want is not None and want.lower() not in {c.lower() for c in _ASSIGNED.values()}:
                _ASSIGNED[n] = want
        for n in names:
            if n not in _ASSIGNED:
                _assign(n)


def resolve(name_or_label: str) -> str:
    """The model name a figure's name or free-text label refers to.

    Exact names win; then an exact label (any case); then the longest label the text
    starts with; then the longest known name the normalised text contains ("Hertz,
    first order" -> ``hertz``). Text that names no known model is its own name (and gets
    its own colour).
    """
    names = model_names()
    if name_or_label in names:
        return name_or_label
    low = name_or_label.strip().lower()
    known = sorted(((lab.lower(), n) for n in names
                    for lab in (label(n), _pipeline_labels().get(n, "")) if lab),
                   key=lambda t: len(t[0]), reverse=True)
    for lab, n in known:
        if low == lab:
            return n
    for lab, n in known:  # "viscoelastic (split η): fit" names viscoelastic_split
        if low.startswith(lab):
            return n
    key = re.sub(r"[\s\-_]", "", low)
    for n in sorted(names, key=len, reverse=True):
        if n.replace("_", "") in key:
            return n
    return name_or_label


def color(name: str) -> str:
    """Colour of model ``name`` (a name or a label: see :func:`resolve`)."""
    _ensure_known()
    key = resolve(name)
    return _ASSIGNED.get(key) or _assign(key)


def colors(names: Iterable[str]) -> list[str]:
    return [color(n) for n in names]


def label(name: str) -> str:
    """Display label of model ``name``: the registry's, else the pipeline's, else the name."""
    law = _registry_law(name)
    text = law.presentation.label if law is not None else None
    return str(text or _pipeline_labels().get(name) or name)


_GREEK = ("alpha", "beta", "gamma", "delta", "epsilon", "eta", "theta", "kappa", "lambda",
          "mu", "nu", "rho", "sigma", "tau", "phi", "chi", "psi", "omega", "Delta", "Gamma")
_GREEK_RE = re.compile(r"(?<![A-Za-z\\$])(" + "|".join(_GREEK) + r")(0|_[A-Za-z0-9]+)?(?![A-Za-z])")


def _symbol(m: re.Match) -> str:
    sub = m.group(2) or ""
    if sub == "0":
        return rf"$\{m.group(1)}_0$"
    if sub:
        s = sub[1:]
        s = s if len(s) == 1 else rf"\mathrm{{{s}}}"
        return rf"$\{m.group(1)}_{{{s}}}$"
    return rf"$\{m.group(1)}$"


def tex(text: str) -> str:
    """``text`` with Greek words as mathtext symbols: "shared eta" -> "shared $\\eta$",
    "eta_Q" -> "$\\eta_Q$", "delta0" -> "$\\delta_0$". Text already holding ``$`` is kept."""
    if "$" in text:
        return text
    return _GREEK_RE.sub(_symbol, text)


_NUISANCE = {
    "delta0": r"$\delta_0$", "delta0_scatter": r"$\sigma_{\ln\delta_0}$",
    "delta0_ref_log": r"$\ln\delta_{0,\mathrm{ref}}$", "sigma_shift": r"$\sigma_\mathrm{shift}$",
    "kappa_shift": r"$\kappa_\mathrm{shift}$", "tau_shift": r"$\tau_\mathrm{shift}$",
    "sigma_amp": r"$\sigma_\mathrm{amp}$", "tau_amp": r"$\tau_\mathrm{amp}$",
    "offset_amp_down": r"$\Delta_\mathrm{amp}$", "loss_exponent": r"$\beta$",
    "loss_gain": r"$g_\mathrm{loss}$", "loss_power": r"$p_\mathrm{loss}$",
    "offset_down": r"$\Delta_\mathrm{down}$", "sigma_logq": r"$\sigma_{\ln Q}$",
    "mu_logq": r"$\mu_{\ln Q}$", "tau_logq": r"$\tau_{\ln Q}$", "mu_f0": r"$\mu_{f_0}$",
    "tau_f0": r"$\tau_{f_0}$", "amp": r"$a_\mathrm{base}$", "power": r"$p_\mathrm{base}$",
    "young": r"$E$", "e_star": r"$E^*$", "n": r"$n$", "gamma": r"$\gamma$", "eta": r"$\eta$",
    "eta_shift": r"$\eta_\mathrm{shift}$", "eta_q": r"$\eta_Q$", "f0": r"$f_0$",
    "f0_pred": r"$f_{0,\mathrm{pred}}$", "q_pred": r"$Q_\mathrm{pred}$",
}


def param_label(name: str) -> str:
    """Symbol of parameter ``name`` (``"eta"`` -> ``$\\eta$``); a vector element keeps its
    index (``"delta0[3]"`` -> ``$\\delta_0$[3]``). The registry's ``Param.label`` wins."""
    base, _, rest = name.partition("[")
    idx = f"[{rest}" if rest else ""
    for law in _registry_laws():
        for p in getattr(law, "params", ()):
            if getattr(p, "name", None) == base and getattr(p, "label", None):
                return f"{p.label}{idx}"
    return f"{_NUISANCE.get(base, tex(base))}{idx}"


def axis_label(name: str, unit: str | None) -> str:
    """``symbol [unit]`` for an axis; ``[-]`` for a dimensionless quantity."""
    return f"{param_label(name)} [{unit or '-'}]"
