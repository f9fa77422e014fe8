"""The contact-law object: everything the project knows about one law, in one place.

A law is a :class:`ContactLaw` built in the law's own module (``models/laws/hertz.py`` holds
``LAW``, and so on) and listed once, in :mod:`models.registry`. It carries

* its parameters (:class:`Param`: name, unit, label, prior, description);
* its force ``F(delta; theta, scene)`` [N], a JAX-traceable function of the overlap
  delta [m] and keyword parameters (law parameters and scene quantities by name);
* optional fast paths: closed forms or tables of the static overlap, of the overlap a
  measured resonance implies, and of the shift at a rung. Anything not given is
  computed by the generic numerics of :mod:`models.ladder.generic` from the force alone;
* its linear Q where it has a loss channel, its rungs and its reference.

These come in three groups, each a small frozen dataclass: :class:`Physics` (the force,
the fast paths, the rungs: what the law computes), :class:`SamplerHints` (how the
inference samples and schedules it) and :class:`Presentation` (its label, reference,
colour and description: how it is shown). A reader asks the group:
``law.physics.force``, ``law.sampler.cost``, ``law.presentation.label``.

Keyword conventions. Every function of a law receives the *resolved* keywords of
:meth:`ContactLaw.resolve`: the scene quantities of :data:`SCENE_KEYS` (``radius`` [m],
``young`` [Pa], ``poisson`` [-], ``e_star`` [Pa], ``load`` [N], ``mass`` [kg],
``gravity`` [m/s^2], ``roughness_rms`` [m], ``surface_energy`` [J/m^2]) overlaid by the
law parameters; ``e_star`` = E/(2 (1 - nu^2)) (identical bead and rod) is recomputed from
``young`` and ``poisson`` unless ``e_star`` is itself a law parameter. Functions take
what they need by name and ignore the rest (``**_``).

Protocol-to-protocol scatter (remounting the bead). By default the law's stiffness
scale scatters: F_p = s_p F(delta; theta), so the measured f0_p fixes the static
overlap through F(delta0)/F'(delta0) = F0/(m omega0_p^2), independently of s_p
(:func:`models.ladder.generic.overlap_from_frequency`: Hertz gives 3 F0/(2 m omega0^2), a power
law n F0/(m omega0^2)). A law whose scatter enters otherwise overrides
``overlap_from_frequency`` in its own module and says why there.

Priors are described by :class:`Prior` (``models/`` imports no NumPyro; ``inference``
turns them into distributions). A law loaded from a user's file may give NumPyro
distributions directly.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import jax.numpy as jnp
import numpy as np

from beadrod.models.rungs import LADDER

__all__ = ["Prior", "Param", "Prepared", "Physics", "SamplerHints", "Presentation", "ContactLaw",
           "SCENE_KEYS", "RungUnavailable", "effective_modulus", "prior_median", "sampler_site"]

SCENE_KEYS = ("radius", "young", "poisson", "e_star", "load", "mass", "gravity",
              "roughness_rms", "surface_energy")
"""Scene quantities a law function may ask for by name (units in the module docstring)."""


class RungUnavailable(ValueError):
    """The law has no implementation of the requested rung."""


def effective_modulus(young: Any, poisson: Any) -> Any:
    """E* = E / (2 (1 - nu^2)) [Pa] for identical bead and rod (Johnson 1985, Eq. 4.22)."""
    return young / (2.0 * (1.0 - poisson * poisson))


@dataclass(frozen=True)
class Prior:
    """A proper prior described without NumPyro.

    ``kind``: 'uniform' (a, b) = bounds; 'loguniform' (a, b) = bounds; 'lognormal'
    (a, b) = (median, sigma of the log); 'normal' (a, b) = (mean, sd); 'halfnormal'
    (a,) = scale.
    """

    kind: str
    a: float
    b: float = 0.0

    def median(self) -> float:
        return {"uniform": lambda: 0.5 * (self.a + self.b),
                "loguniform": lambda: math.sqrt(self.a * self.b),
                "lognormal": lambda: self.a,
                "normal": lambda: self.a,
                "halfnormal": lambda: self.a * 0.6744897501960817}[self.kind]()

    def bounds(self) -> tuple[float, float]:
        """Support [lo, hi] (infinite ends as +-inf)."""
        if self.kind in ("uniform", "loguniform"):
            return self.a, self.b
        if self.kind in ("lognormal", "halfnormal"):
            return 0.0, math.inf
        return -math.inf, math.inf

    def describe(self, scale: float = 1.0) -> str:
        s = lambda v: f"{v / scale:.4g}"
        return {"uniform": lambda: f"Uniform({s(self.a)}, {s(self.b)})",
                "loguniform": lambda: f"LogUniform({s(self.a)}, {s(self.b)})",
                "lognormal": lambda: f"LogNormal(median {s(self.a)}, sd of log {self.b:.3g})",
                "normal": lambda: f"Normal({s(self.a)}, {s(self.b)})",
                "halfnormal": lambda: f"HalfNormal({s(self.a)})"}[self.kind]()


def prior_median(prior: Any) -> float:
    """Median of a :class:`Prior` or a NumPyro distribution (icdf(0.5), else its mean)."""
    if isinstance(prior, Prior):
        return prior.median()
    try:
        return float(prior.icdf(jnp.asarray(0.5)))
    except (NotImplementedError, AttributeError, TypeError):
        return float(prior.mean)


@dataclass(frozen=True)
class Param:
    """A law parameter: sample-site name, unit, display label (LaTeX), prior, meaning.

    ``display`` = (unit, scale): how tables show it (e.g. ('GPa', 1e9)). ``scene_key``:
    the scene quantity that gives its nominal value (``beadrod shift`` uses it when the
    parameter is not given; otherwise the prior median). ``domain``: [lo, hi] (``(lo, hi]``
    with ``open_low``), the values for which the law's functions are defined (outside
    them they return NaN); None: every value its prior's kind allows. ``bounds``: the
    :data:`models.scene.BOUNDS` key of the physical range of its quantity. ``what``:
    what it is, in messages. The commands refuse a value outside either
    (:meth:`problem`).
    """

    name: str
    unit: str
    label: str
    prior: Any
    description: str
    display: tuple[str, float] | None = None
    scene_key: str | None = None
    domain: tuple[float, float] | None = None
    open_low: bool = False
    bounds: str | None = None
    what: str = ""

    def domain_text(self) -> str | None:
        """The domain as an interval, e.g. '(1, 3]' (None: no domain)."""
        if self.domain is None:
            return None
        lo, hi = self.domain
        return f"{'(' if self.open_low else '['}{lo:g}, {hi:g}]"

    def bounds_range(self) -> tuple[float, float, str] | None:
        """(low, high, why) of the physical bounds of its quantity (None: none)."""
        if self.bounds is None:
            return None
        from beadrod.models.scene import BOUNDS

        return BOUNDS[self.bounds]

    def problem(self, value: float) -> str | None:
        """Why ``value`` cannot be this parameter's value (not finite, outside its domain
        or its quantity's physical bounds), or None."""
        v = float(value)
        what = self.what or self.name
        unit = "" if self.unit in ("-", "?") else f" {self.unit}"
        if not math.isfinite(v):
            return f"{self.name} = {value}: must be a finite number"
        if self.domain is not None:
            lo, hi = self.domain
            if not ((lo < v if self.open_low else lo <= v) and v <= hi):
                return (f"{self.name} = {v:g}: {what} is defined for {self.name} in "
                        f"{self.domain_text()}{unit} (its domain, `beadrod laws`)")
        rng = self.bounds_range()
        if rng is not None and not rng[0] <= v <= rng[1]:
            return (f"{self.name} = {v:g}: {what} must lie in [{rng[0]:g}, {rng[1]:g}]{unit} "
                    f"({rng[2]})")
        return None


@dataclass(frozen=True)
class Prepared:
    """An intermediate ``compute(**kw)`` that several of a law's functions read, computed
    once by :meth:`ContactLaw.resolve` and stored in the keywords under ``name`` with the
    objects of ``inputs`` (keyword names) it was computed from.

    Why the objects are kept: keywords are plain dicts, and a caller may change one
    after resolve (``{**kw, "gamma": 2.0}``) or build them by hand; :meth:`value` uses
    the stored result only while every input is the same object (checked while tracing,
    nothing in a compiled program), else computes it afresh: never stale, at worst not
    shared."""

    name: str
    inputs: tuple[str, ...]
    compute: Callable[..., Any]

    def entry(self, kw: Mapping[str, Any]) -> dict[str, Any]:
        """``{name: (inputs, value)}`` for :meth:`ContactLaw.resolve` (empty if an input
        is missing)."""
        if not all(k in kw for k in self.inputs):
            return {}
        return {self.name: (tuple(kw[k] for k in self.inputs), self.compute(**kw))}

    def value(self, kw: Mapping[str, Any]) -> Any:
        """The stored value if ``kw`` still holds the objects it was computed from, else
        ``compute(**kw)``."""
        got = kw.get(self.name)
        if (isinstance(got, tuple) and len(got) == 2
                and all(a is kw.get(k) for a, k in zip(got[0], self.inputs))):
            return got[1]
        return self.compute(**kw)


@dataclass(frozen=True, eq=False)
class Physics:
    """What a law computes: its force, the fast paths that replace the generic numerics,
    its rungs and their domains.

    ``force(delta, **kw)`` [N] is required. Optional fast paths, each called with the
    resolved keywords (:meth:`ContactLaw.resolve`):

    * ``static_overlap(**kw)`` -> delta0 [m] under ``load``;
    * ``overlap_from_frequency(f0, **kw)`` -> delta0 [m] a measured f0 [Hz] implies;
    * ``frequency_from_overlap(delta0, **kw)`` -> f0 [Hz], its inverse
      (:meth:`ContactLaw.frequency_at`; a law that sets ``overlap_from_frequency`` with a
      scatter treatment of its own should set it, else the inverse is a Newton solve of
      ``overlap_from_frequency``);
    * ``shifts``: rung name -> ``fn(x, **kw)`` with ``delta0`` [m] and ``omega0``
      [rad/s] among the keywords (per sweep);
    * ``linear_q(**kw)`` (with ``omega0``) -> Q [-], for laws with a loss channel;
    * ``restoring_force(**kw)`` (with ``delta0``) -> (P', divided, flight acceleration) of
      the dimensionless oscillator, as :func:`models.ladder.generic.restoring_force` computes them
      from the force: an exact form that is cheaper, for a law whose force is itself a
      root solve (the generic backbone then evaluates no force);
    * ``contact_edge(**kw)`` -> the overlap [m] below which the surfaces separate
      (default 0: unilateral contact; adhesive laws hold on to negative overlaps);
    * ``domains``: rung name -> ``fn(x, **kw)`` -> bool array, True where that rung's
      fast path is valid (a table's range). Outside it the fast path returns a held
      value, so samplers must not count it: the inference gives the point zero
      likelihood (:meth:`ContactLaw.in_domain`). A rung with no entry is valid everywhere.

    ``rungs``: the rungs the law computes (those of :data:`models.rungs.FIT_RUNGS` are the
    ones it can be fitted at); those without a ``shifts`` entry are served by
    :mod:`models.ladder.generic` and :mod:`models.ladder.generic_dynamics` (exact, slow).

    ``prepared``: :class:`Prepared` intermediates that several of the law's functions read
    (Maugis-Dugdale's static state). :meth:`ContactLaw.resolve` computes each once and adds
    it to the keywords; the functions read it with :meth:`Prepared.value`, which recomputes
    it where the keywords no longer hold the objects it was computed from. In a sampler's
    step it is then computed once instead of at every place the log density reads it (and
    its gradient taken once).

    ``table``: the specification of the law's stored backbone table
    (:class:`models.tables.shape_spec.ShapeTable`), for a law whose exact backbone depends
    on a shape parameter at a given load; None where the law has no such table.

    The loss, in L(x) = q(x)/k0 [-] (the quadrature stiffness at amplitude x over the
    linear stiffness; 1/Q at x -> 0), which the resonance amplitude per volt measures
    (docs/damping.md):

    * ``loss_exponent``: how the law's own linear loss scales with the resonance,
      L0 Omega^beta (Kuwabara-Kono damping: 3, as q = A omega k_eq and k_eq = m omega^2 on
      the backbone). None: the law has no loss of its own; the comparison gives it the
      background loss L0 Omega^beta with beta fitted (from 0, a constant loss factor, to 3,
      radiation into the rod).
    * ``loss_increment(x, **kw)`` -> the loss the law adds that grows with the amplitude,
      Delta L(x) [-] (hysteresis: h rho(m) x^(m-1)); None: none.
    """

    force: Callable[..., Any]
    rungs: tuple[str, ...] = LADDER
    shifts: Mapping[str, Callable[..., Any]] = field(default_factory=dict)
    static_overlap: Callable[..., Any] | None = None
    overlap_from_frequency: Callable[..., Any] | None = None
    frequency_from_overlap: Callable[..., Any] | None = None
    linear_q: Callable[..., Any] | None = None
    restoring_force: Callable[..., Any] | None = None
    contact_edge: Callable[..., Any] | None = None
    domains: Mapping[str, Callable[..., Any]] = field(default_factory=dict)
    prepared: tuple[Prepared, ...] = ()
    table: Any = None
    loss_exponent: float | None = None
    loss_increment: Callable[..., Any] | None = None


@dataclass(frozen=True, eq=False)
class SamplerHints:
    """How the inference should sample and schedule a law: hints that change no value the
    law computes.

    ``scales``: parameter name -> ``s(**others)`` > 0, a function of the law's parameters
    that have no scale of their own. The sampler then moves in p s (its unconstrained
    coordinate: ln(p s) for a positive p) instead of p, at site :func:`sampler_site` (p
    stays a deterministic site of that name); p's prior is unchanged (a change of
    variables). For a posterior ridge along which the data fix p s and not p, which a dense
    mass matrix cannot follow where s varies over the other parameters' range (the law
    says why in its module). :class:`ContactLaw` checks that each names one of its
    parameters.

    ``cost``: a fit's relative wall time (1 = a closed-form law), used only to start the
    costliest fits first.
    """

    scales: Mapping[str, Callable[..., Any]] = field(default_factory=dict)
    cost: float = 1.0


@dataclass(frozen=True, eq=False)
class Presentation:
    """How a law is named and shown: in tables, figures, reports and ``beadrod laws``.

    ``label``: its display name; ``reference``: where its physics comes from;
    ``color``: its colour in figures (a '#rrggbb' string; None: one is assigned);
    ``description``: one paragraph on what it is (``beadrod laws``).
    ``in_default_comparison`` False keeps a law out of ``beadrod compare`` unless it is
    asked for by name (the law says why in its ``description``).

    ``tension_role`` ('shared' or 'split') and ``tension_param`` mark the pair of laws
    behind the Q-versus-shift tension (:func:`models.registry.tension_pair`):
    ``tension_param`` names the loss parameter of the shared law, which the split law
    carries as ``<tension_param>_shift`` and ``<tension_param>_q``.
    """

    label: str
    reference: str = ""
    color: str | None = None
    description: str = ""
    in_default_comparison: bool = True
    tension_role: str | None = None
    tension_param: str | None = None


@dataclass(frozen=True, eq=False)
class ContactLaw:
    """One contact law (see the module docstring). Instances compare by identity.

    ``name``: its registry name (``--law``); ``params``: its :class:`Param` s;
    ``physics``: what it computes (:class:`Physics`); ``presentation``: how it is named and
    shown (:class:`Presentation`); ``sampler``: hints for the inference
    (:class:`SamplerHints`); ``source``: 'built-in' or the path of the law file it came
    from.
    """

    name: str
    params: tuple[Param, ...]
    physics: Physics
    presentation: Presentation
    sampler: SamplerHints = field(default_factory=SamplerHints)
    source: str = "built-in"

    def __post_init__(self) -> None:
        names = set(self.param_names)
        for name in self.sampler.scales:
            if name not in names:
                raise ValueError(f"law '{self.name}': sampler.scales names {name!r}, which is "
                                 f"not one of its parameters {sorted(names)}")

    # ------------------------------------------------------------------ parameters
    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)

    @property
    def predicts_q(self) -> bool:
        return self.physics.linear_q is not None

    def too_slow_for_nuts(self, rung: str) -> bool:
        """True where a built-in law has ``rung`` only as the generic quadrature (no closed
        form or table): that quadrature at every likelihood call is too slow for NUTS. A law
        file's law is never so marked: its file asked for the rung."""
        return (rung in self.physics.rungs and rung not in self.physics.shifts
                and self.source == "built-in")

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(f"law '{self.name}' has no parameter {name!r}; it has "
                       f"{list(self.param_names)}")

    def sampler_values(self, values: Mapping[str, Any]) -> dict[str, Any]:
        """``values`` with each parameter that has a sampler scale given at its sample site
        instead (:func:`sampler_site`: the value times its scale, computed from the other
        parameters in ``values``, which must be there); other keys pass through."""
        out = {k: v for k, v in values.items() if k not in self.sampler.scales}
        others = {k: v for k, v in values.items()
                  if k in self.param_names and k not in self.sampler.scales}
        missing = [p for p in self.param_names
                   if p not in self.sampler.scales and p not in values]
        for name, scale in self.sampler.scales.items():
            if name not in values:
                continue
            if missing:
                raise ValueError(f"law '{self.name}': {name} is sampled scaled by the other "
                                 f"parameters; give {missing} with it")
            out[sampler_site(name)] = values[name] * scale(**others)
        return out

    def resolve(self, scene: Mapping[str, Any], theta: Mapping[str, Any]) -> dict[str, Any]:
        """Keywords for the law's functions: scene quantities overlaid by ``theta``.

        ``e_star`` follows ``young`` and ``poisson`` unless it is a law parameter; the
        law's ``physics.prepared`` intermediates are added (:class:`Prepared`).
        """
        kw = {k: scene[k] for k in SCENE_KEYS if k in scene}
        kw.update(theta)
        if "e_star" not in self.param_names and "young" in kw and "poisson" in kw:
            kw["e_star"] = effective_modulus(kw["young"], kw["poisson"])
        for item in self.physics.prepared:
            kw.update(item.entry(kw))
        return kw

    # --------------------------------------------------------------------- physics
    def overlap(self, **kw: Any) -> Any:
        """Static overlap delta0 [m] under ``load`` (fast path or generic root solve)."""
        if self.physics.static_overlap is not None:
            return self.physics.static_overlap(**kw)
        from beadrod.models.ladder.generic import static_overlap

        return static_overlap(self, **kw)

    def overlap_at(self, f0: Any, **kw: Any) -> Any:
        """delta0 [m] that the measured linear resonance f0 [Hz] implies (see module doc)."""
        if self.physics.overlap_from_frequency is not None:
            return self.physics.overlap_from_frequency(f0, **kw)
        from beadrod.models.ladder.generic import overlap_from_frequency

        return overlap_from_frequency(self, f0, **kw)

    def frequency_at(self, delta0: Any, **kw: Any) -> Any:
        """f0 [Hz] of a protocol whose static overlap is delta0 [m]: the inverse of
        :meth:`overlap_at`. The law's closed form; for the default scatter treatment
        (no ``overlap_from_frequency``) omega0^2 = load F'(delta0)/(m F(delta0)); else a
        Newton solve of :meth:`overlap_at` (:func:`models.ladder.generic.frequency_from_overlap`).
        """
        from beadrod.models.ladder import generic

        if self.physics.frequency_from_overlap is not None:
            return self.physics.frequency_from_overlap(delta0, **kw)
        if self.physics.overlap_from_frequency is None:
            return generic.stiffness_scale_frequency(self, delta0, **kw)
        return generic.frequency_from_overlap(self, delta0, **kw)

    def edge(self, **kw: Any) -> Any:
        """Overlap [m] at which contact is lost (0 unless the law is adhesive)."""
        return 0.0 if self.physics.contact_edge is None else self.physics.contact_edge(**kw)

    def shift(self, x: Any, *, rung: str, fast: bool = True, **kw: Any) -> Any:
        """Delta f/f0 [-] at x = delta_a/delta0 on ``rung``.

        ``kw`` are resolved keywords plus ``delta0`` [m] (the overlap x refers to; the
        law's static overlap under ``load`` when absent) and ``omega0`` [rad/s].
        A fast path is used when the law has one and ``fast`` (outside its domain,
        :meth:`in_domain`, it holds a value that is not the law's); otherwise the generic
        quadrature of
        :mod:`models.ladder.generic` (exact, but far too slow for a sampler), or for 'series',
        'harmonic_balance' and 'time_integration' :mod:`models.ladder.generic_dynamics` (options
        ``q_factor``, ``harmonics``, ... there).
        """
        if rung not in self.physics.rungs:
            raise RungUnavailable(
                f"law '{self.name}' has no rung {rung!r}; its rungs are "
                f"{list(self.physics.rungs)}")
        fn = self.physics.shifts.get(rung) if fast else None
        if fn is not None:
            return fn(jnp.asarray(x, float), **kw)
        from beadrod.models.ladder import generic

        if "delta0" not in kw:
            kw = {**kw, "delta0": self.overlap(**kw)}
        if rung == "first_order":
            return generic.first_order_shift(self, x, **kw)
        if rung == "backbone":
            return generic.backbone_shift(self, x, **kw)
        from beadrod.models.ladder import generic_dynamics

        run = {"series": generic_dynamics.series_shift,
               "harmonic_balance": generic_dynamics.hbm_shift,
               "time_integration": generic_dynamics.timeint_shift}.get(rung)
        if run is not None:
            return run(self, x, **kw)
        raise RungUnavailable(f"law '{self.name}': rung {rung!r} has no generic form; "
                              "give it in the law's shifts")

    def shift_everywhere(self, x: Any, *, rung: str, **kw: Any) -> tuple[Any, Any]:
        """(Delta f/f0 [-], outside) at concrete amplitudes x (numpy, not traced): the fast
        path where it holds, the generic quadrature where it does not (``outside``, a bool
        array: there the fast path would hold a value that is not the law's). For commands
        that print values; a sampler counts no point outside instead (:meth:`in_domain`)."""
        xa = np.asarray(x, float)
        values = np.array(self.shift(xa, rung=rung, **kw), float)
        inside = self.in_domain(xa, rung=rung, **kw)
        outside = (np.zeros(xa.shape, bool) if inside is None
                   else ~np.broadcast_to(np.asarray(inside, bool), xa.shape))
        if outside.any():
            values[outside] = np.asarray(self.shift(xa[outside], rung=rung, fast=False, **kw),
                                         float)
        return values, outside

    def in_domain(self, x: Any, *, rung: str, **kw: Any) -> Any:
        """Bool array: True where ``rung``'s fast path holds at x (same keywords as
        :meth:`shift`); None where the rung has no limited domain."""
        fn = self.physics.domains.get(rung) if rung in self.physics.shifts else None
        return None if fn is None else fn(jnp.asarray(x, float), **kw)

    def loss(self, x: Any, *, linear_loss: Any, omega_ratio: Any,
             background_exponent: Any = 0.0, **kw: Any) -> Any:
        """L(x) = q(x)/k0 [-] at amplitude x = delta_a/delta0: the linear loss
        ``linear_loss`` (1/Q0) scaled by the resonance ratio ``omega_ratio`` to the law's
        ``loss_exponent`` (else ``background_exponent``), plus its ``loss_increment``."""
        beta = (background_exponent if self.physics.loss_exponent is None
                else self.physics.loss_exponent)
        out = linear_loss * omega_ratio ** beta
        if self.physics.loss_increment is not None:
            out = out + self.physics.loss_increment(x, **kw)
        return out

    @property
    def has_own_loss(self) -> bool:
        """True where the law's loss is its own (no fitted background exponent)."""
        return self.physics.loss_exponent is not None

    def quality_factor(self, **kw: Any) -> Any:
        """Linear Q [-] at ``omega0`` [rad/s]."""
        if self.physics.linear_q is None:
            raise ValueError(f"law '{self.name}' predicts no linear Q (no loss channel)")
        return self.physics.linear_q(**kw)

    def describe(self) -> dict[str, Any]:
        """JSON-ready description (``beadrod laws --json``)."""
        return {
            "name": self.name, "label": self.presentation.label,
            "reference": self.presentation.reference, "source": self.source,
            "rungs": list(self.physics.rungs), "predicts_q": self.predicts_q,
            "description": self.presentation.description,
            "params": [{"name": p.name, "unit": p.unit, "label": p.label,
                        "description": p.description, "prior": _prior_text(p),
                        "domain": None if p.domain is None else list(p.domain),
                        "domain_open_low": p.open_low, "domain_text": p.domain_text(),
                        "bounds": None if p.bounds is None else list(p.bounds_range()[:2]),
                        "sampled_as": (sampler_site(p.name) if p.name in self.sampler.scales
                                       else None)}
                       for p in self.params],
        }


def sampler_site(name: str) -> str:
    """The sample site of parameter ``name`` when its law gives it a sampler scale
    (:attr:`SamplerHints.scales`): the value times the scale."""
    return f"{name}_scaled"


def _prior_text(p: Param) -> str:
    if isinstance(p.prior, Prior):
        if p.display is not None:
            unit, scale = p.display
            return f"{p.prior.describe(scale)} {unit}"
        return p.prior.describe() + ("" if p.unit in ("-", "?") else f" {p.unit}")
    # a law file's numpyro distribution: its class and scalar arguments, in SI units (its
    # repr is an object address)
    args = []
    for k in getattr(p.prior, "arg_constraints", {}):
        v = np.asarray(getattr(p.prior, k, np.nan))
        args.append(f"{k}={float(v):g}" if v.size == 1 else f"{k}=<{v.size} values>")
    unit = "" if p.unit in ("-", "?") else f" {p.unit}"
    return f"{type(p.prior).__name__}({', '.join(args)}){unit}"


YOUNG = Param(
    "young", "Pa", r"$E$", Prior("uniform", 150e9, 250e9),
    "Young's modulus of bead and rod (taken equal). Prior Uniform(150, 250) GPa: "
    "austenitic/martensitic stainless and carbon steels span about 180-215 GPa (paper: "
    "190-210 GPa); the wider band leaves room for near-surface damage and grade "
    "uncertainty without admitting non-steels.",
    display=("GPa", 1e9), scene_key="young", bounds="young_Pa", what="Young's modulus")
"""E, shared by every law whose force is set by the elastic modulus."""

GAMMA = Param(
    "gamma", "J/m^2", r"$\gamma$", Prior("lognormal", 0.7, 0.5),
    "Surface energy of each surface (work of adhesion w = 2 gamma). Prior LogNormal("
    "median 0.7, sd of log 0.5) J/m^2: clean steel-steel surfaces are of order 1 J/m^2, "
    "contaminated ones (air, oxide) a few tenths; the paper uses 0.7. Defined for gamma > 0 "
    "(at gamma = 0 an adhesive law is Hertz's: `--law hertz`).",
    scene_key="surface_energy", domain=(0.0, 10.0), open_low=True,
    bounds="surface_energy_J_m2", what="the surface energy")
"""gamma, shared by the adhesive laws."""

__all__ += ["YOUNG", "GAMMA"]
