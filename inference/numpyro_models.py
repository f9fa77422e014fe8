"""NumPyro models of the bead-rod data, one per contact law, built from ``models/`` only.

Structure shared by every law (names are the sample sites):

* Global law parameters (``young``, ``eta``, ``n``, ``gamma``, ...; priors in
  :mod:`inference.priors`).
* Per-protocol static overlap, hierarchical in log around the law's static overlap
  under the bead's weight, delta0_ref:
  ``log delta0_p ~ Normal(log delta0_ref, delta0_scatter)`` (site ``delta0_log``).
* The measured linear resonance of each protocol ties delta0_p to the law through its
  tangent stiffness: ``f0_obs_p ~ Normal(sqrt(K_law(delta0_p)/m) / 2 pi, f0_sd)`` with a
  known measurement sd ``ModelSpec.f0_sd`` (default 5 Hz: peak-picking repeatability of
  a low-amplitude sweep at 2.7 kHz). All f0 scatter beyond it is delta0 scatter.
* Drive sweeps: x_i = delta_a,i / delta0_p(i); the rung gives Delta f/f0(x_i) and
  ``shift_obs_i ~ Normal|StudentT(shift(x_i) + offset_down * direction_i, sigma_shift)``.
  Up and down sweeps share one curve; down sweeps (direction = 1) get one extra offset
  (the delayed jump of a softening resonance biases their peak low).
* Reference Q where the protocol has one: the viscoelastic law predicts
  Q_p = 1/(omega0_p A(eta, E)) and ``q_obs ~ LogNormal(log Q_p, sigma_logq)``; laws that
  predict no Q get a law-free nuisance model log Q ~ Normal(mu_logq, tau_logq), so every
  model describes the same data and evidences are comparable.

Rungs (``ModelSpec.rung``):
  'first_order'  paper's averaged tangent stiffness: models.shift.first_order_hertz /
                 first_order_powerlaw; for viscoelastic the correct law
                 models.viscoelastic.shift_first_order (damping does not enter);
                 for JKR models.jkr.shift_first_order.
  'paper_eq25'   viscoelastic only: models.viscoelastic.shift_paper_eq25 (the paper's
                 curve, secant-slope artefact included; eta enters the shift).
  'backbone'     exact conservative backbone models.backbone.backbone_shift(x, n)
                 (power laws: Hertz, viscoelastic at n = 3/2, power law at n).

The law-free ``baseline``: Delta f/f0 = -amp * xs^power with xs = delta_a omega0_p^2 / g
(the overlap scale g/omega0^2 of a linear spring; any other scale is absorbed into amp),
f0_obs ~ Normal(mu_f0, tau_f0), the nuisance Q model. It fits any smooth monotone
softening: a law that loses to it is missing the data's shape.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import jax
import jax.numpy as jnp
import numpyro
import numpyro.distributions as dist

from models import hertz, materials, powerlaw

from .likelihood import observe_logq, observe_shift
from .priors import prior

__all__ = ["LAWS", "RUNGS", "ModelSpec", "ForwardModelUnavailable", "build_model",
           "paper_spec", "shift_forward", "check_backbone"]

LAWS = ("hertz", "powerlaw", "viscoelastic", "jkr", "baseline")
RUNGS = ("first_order", "paper_eq25", "backbone")


class ForwardModelUnavailable(RuntimeError):
    """The requested rung's forward function is not available in ``models/``."""


@dataclass(frozen=True)
class ModelSpec:
    """What to build. ``eta_mode`` 'split' gives eta_shift (shift) and eta_q (Q)."""

    law: str = "hertz"
    rung: str = "first_order"
    eta_mode: str = "shared"
    use_shift: bool = True
    use_q: bool = True
    use_f0: bool = True
    likelihood: str = "normal"
    student_df: float = 4.0
    f0_sd: float = 5.0
    overrides: dict[str, Any] = field(default_factory=dict, hash=False, compare=False)

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise ValueError(f"unknown law {self.law!r}; choose from {LAWS}")
        if self.rung not in RUNGS:
            raise ValueError(f"unknown rung {self.rung!r}; choose from {RUNGS}")
        if self.rung == "paper_eq25" and self.law != "viscoelastic":
            raise ValueError("rung 'paper_eq25' exists only for the viscoelastic law")
        if self.eta_mode not in ("shared", "split"):
            raise ValueError("eta_mode must be 'shared' or 'split'")
        if self.eta_mode == "split" and self.law != "viscoelastic":
            raise ValueError("eta_mode 'split' exists only for the viscoelastic law")

    @property
    def name(self) -> str:
        parts = [self.law]
        if self.law != "baseline":
            parts.append(self.rung)
        if self.law == "viscoelastic":
            parts.append(f"eta-{self.eta_mode}")
        if self.likelihood != "normal":
            parts.append(self.likelihood)
        if not self.use_shift:
            parts.append("no-shift")
        if not self.use_q:
            parts.append("no-q")
        return "/".join(parts)


def paper_spec(law: str, **kw: Any) -> ModelSpec:
    """The paper's own formulas: first order, and Eq. 25 for the viscoelastic law."""
    return ModelSpec(law=law, rung="paper_eq25" if law == "viscoelastic" else "first_order",
                     **kw)


def _module(name: str):
    try:
        return importlib.import_module(f"models.{name}")
    except ImportError as exc:  # concurrent owners: say exactly what is missing
        raise ForwardModelUnavailable(f"models.{name} is not available: {exc}") from exc


def _function(module: str, name: str) -> Callable:
    fn = getattr(_module(module), name, None)
    if fn is None:
        raise ForwardModelUnavailable(f"models.{module}.{name} is not available")
    return fn


def shift_forward(spec: ModelSpec, x: jnp.ndarray, *, n=None, damping_constant=None,
                  omega=None, jkr_kw: dict | None = None) -> jnp.ndarray:
    """Delta f/f0 at x for ``spec.law`` on ``spec.rung`` (dispatch only, no physics here)."""
    law, rung = spec.law, spec.rung
    if rung == "backbone":
        if law == "jkr":
            raise ForwardModelUnavailable(
                "no backbone rung for JKR: models.backbone.backbone_shift covers F ~ delta^n")
        exponent = hertz.EXPONENT if law in ("hertz", "viscoelastic") else n
        return _function("backbone", "backbone_shift")(x, exponent)
    if law == "hertz":
        return _function("shift", "first_order_hertz")(x)
    if law == "powerlaw":
        return _function("shift", "first_order_powerlaw")(x, n)
    if law == "viscoelastic":
        if rung == "paper_eq25":
            return _function("viscoelastic", "shift_paper_eq25")(
                x, damping_constant=damping_constant, omega=omega)
        return _function("viscoelastic", "shift_first_order")(x)
    if law == "jkr":
        return _function("jkr", "shift_first_order")(x, **jkr_kw)
    raise ValueError(law)


@functools.lru_cache(maxsize=1)
def check_backbone() -> None:
    """Probe models.backbone.backbone_shift once: finite values and gradients in x and n
    where NUTS goes (inside and beyond contact loss), else ForwardModelUnavailable."""
    fn = _function("backbone", "backbone_shift")
    x = jnp.array([0.05, 0.5, 0.95, 1.3])
    n = jnp.array([1.2, 1.5, 2.5])

    @jax.jit
    def probe(x, n):
        total = lambda xx, nn: jnp.sum(fn(xx, nn))
        return jax.vmap(lambda nn: fn(x, nn))(n), jax.grad(total, argnums=(0, 1))(x, n[1])

    val, (gx, gn) = probe(x, n)
    if not (jnp.all(jnp.isfinite(val)) and jnp.all(jnp.isfinite(gx)) and jnp.isfinite(gn)):
        raise ForwardModelUnavailable(
            f"models.backbone.backbone_shift is not finite/differentiable: values {val}, "
            f"d/dx {gx}, d/dn {gn}")


def _delta0(spec: ModelSpec, ref: jnp.ndarray, n_protocols: int) -> jnp.ndarray:
    # Centred in log: f0_p pins delta0_p given the law's parameters, so the posterior of
    # (log E, log delta0_p) is a near-linear ridge (Hertz: delta0_p ~ E^-2 at fixed f0_p)
    # that a dense mass matrix absorbs; the non-centred form bends it through the scatter.
    scatter = numpyro.sample("delta0_scatter", prior("delta0_scatter", spec.overrides))
    with numpyro.plate("protocols", n_protocols):
        log_d = numpyro.sample("delta0_log", dist.Normal(jnp.log(ref), scatter))
    return numpyro.deterministic("delta0", jnp.exp(log_d))


def _nuisance_q(spec: ModelSpec, data: dict) -> None:
    mu = numpyro.sample("mu_logq", prior("mu_logq", spec.overrides))
    tau = numpyro.sample("tau_logq", prior("tau_logq", spec.overrides))
    nq = data["q_idx"].shape[0]
    observe_logq(jnp.full((nq,), mu), tau, data["q_obs"], likelihood=spec.likelihood,
                 df=spec.student_df)


def _observe_f0(spec: ModelSpec, f0_pred: jnp.ndarray, data: dict) -> None:
    # A known measurement sd, not a free one: a free sd competes with the delta0
    # scatter for the same f0 spread (a ridge NUTS cannot cross).
    sigma = spec.f0_sd
    with numpyro.plate("protocols", f0_pred.shape[0]):
        numpyro.sample("f0_obs", dist.Normal(f0_pred, sigma), obs=data["f0"])


def _observe_drive(spec: ModelSpec, curve: jnp.ndarray, data: dict) -> None:
    offset = numpyro.sample("offset_down", prior("offset_down", spec.overrides))
    sigma = numpyro.sample("sigma_shift", prior("sigma_shift", spec.overrides))
    pred = numpyro.deterministic("shift_pred", curve + offset * data["direction"])
    observe_shift(pred, sigma, data["shift"], likelihood=spec.likelihood, df=spec.student_df)


def _baseline(spec: ModelSpec, data: dict) -> None:
    mu = numpyro.sample("mu_f0", prior("mu_f0", spec.overrides))
    tau = numpyro.sample("tau_f0", prior("tau_f0", spec.overrides))
    with numpyro.plate("protocols", data["n_protocols"]):
        f0 = numpyro.sample("f0_obs", dist.Normal(mu, tau), obs=data["f0"])
    if spec.use_shift:
        amp = numpyro.sample("amp", prior("amp", spec.overrides))
        power = numpyro.sample("power", prior("power", spec.overrides))
        omega0 = 2.0 * jnp.pi * jnp.abs(f0)
        xs = data["amplitude"] * jnp.square(omega0[data["proto"]]) / materials.G_STANDARD
        _observe_drive(spec, -amp * jnp.power(xs, power), data)
    if spec.use_q:
        _nuisance_q(spec, data)


def _law_model(spec: ModelSpec, data: dict) -> None:
    law = spec.law
    n_p = data["n_protocols"]
    mass, load, radius = data["mass"], data["load"], data["radius"]
    n = None
    if law == "powerlaw":
        n = numpyro.sample("n", prior("n", spec.overrides))
        ref = jnp.exp(numpyro.sample("delta0_ref_log", prior("delta0_ref_log", spec.overrides)))
        coeff = powerlaw.coefficient_from_overlap(load, ref, n)
        delta0 = _delta0(spec, ref, n_p)
        k0 = powerlaw.stiffness(delta0, coeff=coeff, n=n)
    else:
        young = numpyro.sample("young", prior("young", spec.overrides))
        e_star = materials.effective_modulus(young, data["nu_bead"], young, data["nu_rod"])
        numpyro.deterministic("e_star", e_star)
        if law == "jkr":
            jkr = _module("jkr")
            gamma = numpyro.sample("gamma", prior("gamma", spec.overrides))
            ref = jkr.static_overlap(load, e_star=e_star, radius=radius, gamma=gamma)
            delta0 = _delta0(spec, ref, n_p)
            k0 = jkr.stiffness(delta0, e_star=e_star, radius=radius, gamma=gamma)
        else:
            ref = hertz.static_overlap(load, e_star=e_star, radius=radius)
            delta0 = _delta0(spec, ref, n_p)
            k0 = hertz.stiffness(delta0, e_star=e_star, radius=radius)
    f0_pred = numpyro.deterministic("f0_pred", jnp.sqrt(k0 / mass) / (2.0 * jnp.pi))
    omega0 = 2.0 * jnp.pi * f0_pred
    if spec.use_f0:
        _observe_f0(spec, f0_pred, data)

    a_shift = a_q = None
    if law == "viscoelastic":
        ve = _module("viscoelastic")
        nu = data["nu_bead"]
        if spec.eta_mode == "shared":
            eta_s = eta_q = numpyro.sample("eta", prior("eta", spec.overrides))
        else:
            eta_s = numpyro.sample("eta_shift", prior("eta_shift", spec.overrides))
            eta_q = numpyro.sample("eta_q", prior("eta_q", spec.overrides))
        a_shift = ve.damping_constant(eta1=eta_s, eta2=eta_s, young=young, poisson=nu)
        a_q = ve.damping_constant(eta1=eta_q, eta2=eta_q, young=young, poisson=nu)

    if spec.use_shift:
        p = data["proto"]
        x = data["amplitude"] / delta0[p]
        kw: dict[str, Any] = {}
        if law == "viscoelastic":
            kw = {"damping_constant": a_shift, "omega": omega0[p]}
        elif law == "jkr":
            jkr_load = jkr.force(delta0, e_star=e_star, radius=radius, gamma=gamma)[p]
            kw = {"jkr_kw": {"load": jkr_load, "e_star": e_star, "radius": radius,
                             "gamma": gamma}}
        curve = shift_forward(spec, x, n=n, **kw)
        _observe_drive(spec, curve, data)

    if spec.use_q:
        if law == "viscoelastic":
            sigma = numpyro.sample("sigma_logq", prior("sigma_logq", spec.overrides))
            q_pred = numpyro.deterministic(
                "q_pred", _module("viscoelastic").linear_q(damping_constant=a_q, omega0=omega0))
            observe_logq(jnp.log(q_pred[data["q_idx"]]), sigma, data["q_obs"],
                         likelihood=spec.likelihood, df=spec.student_df)
        else:
            _nuisance_q(spec, data)


def build_model(spec: ModelSpec | str, n_protocols: int | None = None,
                **kw: Any) -> Callable[..., None]:
    """NumPyro model ``model(data)`` for ``spec`` (a ModelSpec or a law name + kwargs).

    ``data`` is :func:`inference.likelihood.model_inputs` (observations under ``f0``,
    ``shift``, ``q_obs``; None entries are simulated: prior/posterior predictive).
    ``n_protocols`` is taken from ``data['f0']`` when observed; give it for prior
    predictive runs without f0.
    """
    if isinstance(spec, str):
        spec = ModelSpec(law=spec, **kw)
    elif kw:
        spec = replace(spec, **kw)
    # import the forward modules now, outside any trace: a first import under jit would
    # turn their module-level jnp constants into leaked tracers
    needed = {"hertz": ["shift"], "powerlaw": ["shift"], "viscoelastic": ["shift", "viscoelastic"],
              "jkr": ["shift", "jkr"], "baseline": []}[spec.law]
    for mod in needed:
        _module(mod)
    if spec.rung == "backbone" and spec.law != "baseline":
        if spec.law == "jkr":
            raise ForwardModelUnavailable(
                "no backbone rung for JKR: models.backbone.backbone_shift covers F ~ delta^n")
        check_backbone()

    def model(data: dict) -> None:
        data = dict(data)
        if "n_protocols" not in data:
            if data.get("f0") is not None:
                data["n_protocols"] = data["f0"].shape[0]
            elif n_protocols is not None:
                data["n_protocols"] = n_protocols
            else:
                raise ValueError("n_protocols is needed when f0 is not observed")
        if spec.law == "baseline":
            _baseline(spec, data)
        else:
            _law_model(spec, data)

    model.spec = spec  # type: ignore[attr-defined]
    return model
