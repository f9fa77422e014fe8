"""NumPyro models of the bead-rod data, one per contact law, built from ``models/`` only.

Structure shared by every law (names are the sample sites):

* Global law parameters (``young``, ``eta``, ``n``, ``gamma``, ...; priors in
  :mod:`inference.priors`).
* The static overlap of each protocol is fixed by its measured linear resonance f0_p:
  at the known load F0 (the bead's weight) the law's tangent stiffness gives
  ``delta0_p = delta0(f0_p; theta)`` (models.hertz / powerlaw / jkr
  ``overlap_from_frequency``: 3 F0/(2 m omega0^2) for Hertz and viscoelastic,
  n F0/(m omega0^2) for the power law, the JKR state at (F0, gamma) for JKR). What
  scatters between protocols (remounting) is the contact's stiffness scale (local
  curvature, E* sqrt(R)), not the load. ``delta0`` is a deterministic site.
* The hierarchical statement ``log delta0_p ~ Normal(log delta0_ref(theta), delta0_scatter)``
  (delta0_ref: the law's overlap under the weight at nominal R) becomes the density of
  the measured f0 (site ``f0_obs``, :class:`MeasuredF0`):

      p(f0_p | theta) = Normal(log delta0(f0_p; theta); log delta0_ref(theta), scatter)
                        * |d log delta0(f0_p; theta) / d f0_p|,

  the Jacobian computed by forward-mode autodiff of the forward map, elementwise. For
  every law here delta0 ~ f0^-2 at fixed load (JKR too: at fixed F0 and gamma,
  a ~ E*^(-1/3) and delta ~ E*^(-2/3) ~ f0^-2), so the Jacobian is 2/f0 and
  theta-independent, but it is not hard-coded. Every model's evidence is therefore a
  density of the same observed variables (f0 [Hz], shift, Q), comparable with the
  law-free baseline's f0 ~ Normal(mu_f0, tau_f0) [Hz].
  This is the sigma_f0 -> 0 limit of a latent-overlap model with f0_obs ~
  Normal(f0(delta0_p), sigma_f0). The neglected measurement noise, ``ModelSpec.f0_sd``
  (5 Hz: peak-picking repeatability of a low-amplitude sweep at 2.7 kHz), is 0.2 % of
  f0, i.e. 0.004 in log delta0, against a fitted scatter of ~0.1 (f0 scatters by
  ~150 Hz over protocols): it changes the f0 variance budget by ~0.1 % and x by 0.4 %.
  Removing those 28 latent dimensions is what makes NUTS and nested sampling cheap.
* Drive sweeps: x_i = delta_a,i / delta0_p(i); the rung gives Delta f/f0(x_i) and
  ``shift_obs_i ~ Normal|StudentT(shift(x_i) + offset_down * direction_i, sigma_shift)``.
  Up and down sweeps share one curve; down sweeps (direction = 1) get one extra offset
  (the delayed jump of a softening resonance biases their peak low).
* Reference Q where the protocol has one: the viscoelastic law predicts
  Q_p = 1/(omega0_p A(eta, E)) with the measured omega0_p = 2 pi f0_p and
  ``q_obs ~ LogNormal(log Q_p, sigma_logq)``; laws that predict no Q get a law-free
  nuisance model log Q ~ Normal(mu_logq, tau_logq), so every model describes the same
  data and evidences are comparable.

Rungs (``ModelSpec.rung``):
  'first_order'  paper's averaged tangent stiffness: models.shift.first_order_hertz /
                 first_order_powerlaw; for viscoelastic the correct law
                 models.viscoelastic.shift_first_order (damping does not enter);
                 for JKR models.jkr.shift_first_order through its table
                 models.jkr_table.shift_first_order_fast: the curve in x = delta_a/delta0
                 (delta0 the JKR overlap implied by f0_p) depends on F0/Fc = F0/(3 pi
                 gamma R) alone, so E* drops out (error <= 2e-7, tests/test_jkr_table.py).
  'paper_eq25'   viscoelastic only: models.viscoelastic.shift_paper_eq25 (the paper's
                 curve, secant-slope artefact included; eta enters the shift).
  'backbone'     exact conservative backbone of F ~ delta^n (Hertz, viscoelastic at
                 n = 3/2, power law at n): models.backbone_table.backbone_shift_fast
                 (tabulated, x in [0, 2], n in [1, 3]) when that module and its table
                 exist, else the quadrature models.backbone.backbone_shift. x is clipped
                 to the table's [0, 2]: beyond it (delta_a > 2 delta0, only for absurd
                 parameters) the curve is held at its x = 2 value, the misfit is left to
                 the likelihood, and no NaN reaches the sampler.

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
import numpy as np
import numpyro
import numpyro.distributions as dist

from models import hertz, materials

from .likelihood import observe_logq, observe_shift
from .overlap import MeasuredF0, _invert_log_overlap, log_overlap
from .priors import prior

__all__ = ["LAWS", "RUNGS", "ModelSpec", "ForwardModelUnavailable", "build_model",
           "paper_spec", "shift_forward", "check_backbone", "MeasuredF0", "log_overlap",
           "curve_draws", "backbone_function"]

LAWS = ("hertz", "powerlaw", "viscoelastic", "jkr", "baseline")
RUNGS = ("first_order", "paper_eq25", "backbone")
# domain of models.backbone_table.backbone_shift_fast
BACKBONE_X_MAX = 2.0


class ForwardModelUnavailable(RuntimeError):
    """The requested rung's forward function is not available in ``models/``."""


@dataclass(frozen=True)
class ModelSpec:
    """What to build. ``eta_mode`` 'split' gives eta_shift (shift) and eta_q (Q).

    ``f0_sd`` [Hz] is the measurement noise of f0 that the exact conditioning on f0
    neglects (documented, not used by the likelihood); ``use_f0=False`` conditions on
    the measured f0 without its density (evidences are then not comparable).
    """

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


@functools.lru_cache(maxsize=1)
def _fast_backbone() -> tuple[Callable, float] | None:
    try:
        mod = importlib.import_module("models.backbone_table")
        fn = mod.backbone_shift_fast
        if bool(jnp.all(jnp.isfinite(fn(jnp.array([0.1, 1.0]), 1.5)))):  # table readable
            return fn, float(getattr(mod, "X_MAX", BACKBONE_X_MAX))
    except Exception:  # noqa: BLE001  (absent module or table: the exact rung is used)
        pass
    return None


def backbone_function() -> tuple[Callable, bool]:
    """(backbone shift function (x, n), is_fast): the tabulated
    models.backbone_table.backbone_shift_fast when its module and data exist, else the
    exact quadrature models.backbone.backbone_shift."""
    fast = _fast_backbone()
    if fast is not None:
        return fast[0], True
    return _function("backbone", "backbone_shift"), False


def shift_forward(spec: ModelSpec, x: jnp.ndarray, *, n=None, damping_constant=None,
                  omega=None, jkr_kw: dict | None = None) -> jnp.ndarray:
    """Delta f/f0 at x for ``spec.law`` on ``spec.rung`` (dispatch only, no physics here)."""
    law, rung = spec.law, spec.rung
    if rung == "backbone":
        if law == "jkr":
            raise ForwardModelUnavailable(
                "no backbone rung for JKR: models.backbone.backbone_shift covers F ~ delta^n")
        exponent = hertz.EXPONENT if law in ("hertz", "viscoelastic") else n
        fn, fast = backbone_function()
        if fast:
            # the table covers x in [0, 2]: clip (see module docstring), never NaN
            x = jnp.clip(x, 0.0, _fast_backbone()[1])
        return fn(x, exponent)
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
        # jkr_kw: load [N], radius [m], gamma [J/m^2] (e_star is not needed: the curve in
        # x depends on F0/Fc alone, models.jkr_table); the table's x range is [0, 2]
        kw = {k: jkr_kw[k] for k in ("load", "radius", "gamma")}
        tab = _module("jkr_table")
        ratio = tab.load_ratio(kw["load"], gamma=kw["gamma"], radius=kw["radius"])
        return tab.shift_first_order_fast(jnp.clip(x, 0.0, tab.X_MAX), ratio)
    raise ValueError(law)


@functools.lru_cache(maxsize=1)
def check_backbone() -> None:
    """Probe the backbone rung once: finite values and gradients in x and n where NUTS
    goes (inside and beyond contact loss), else ForwardModelUnavailable."""
    fn, _ = backbone_function()
    spec = ModelSpec("powerlaw", rung="backbone")
    x = jnp.array([0.05, 0.5, 0.95, 1.3])
    n = jnp.array([1.2, 1.5, 2.5])

    @jax.jit
    def probe(x, n):
        def total(xx, nn):
            return jnp.sum(shift_forward(spec, xx, n=nn))
        return (jax.vmap(lambda nn: shift_forward(spec, x, n=nn))(n),
                jax.grad(total, argnums=(0, 1))(x, n[1]))

    val, (gx, gn) = probe(x, n)
    if not (jnp.all(jnp.isfinite(val)) and jnp.all(jnp.isfinite(gx)) and jnp.isfinite(gn)):
        raise ForwardModelUnavailable(
            f"backbone rung {fn.__module__}.{fn.__name__} is not finite/differentiable: "
            f"values {val}, d/dx {gx}, d/dn {gn}")


def _nuisance_q(spec: ModelSpec, data: dict) -> None:
    mu = numpyro.sample("mu_logq", prior("mu_logq", spec.overrides))
    tau = numpyro.sample("tau_logq", prior("tau_logq", spec.overrides))
    nq = data["q_idx"].shape[0]
    observe_logq(jnp.full((nq,), mu), tau, data["q_obs"], likelihood=spec.likelihood,
                 df=spec.student_df)


def _observe_drive(spec: ModelSpec, curve: jnp.ndarray, data: dict) -> None:
    offset = numpyro.sample("offset_down", prior("offset_down", spec.overrides))
    sigma = numpyro.sample("sigma_shift", prior("sigma_shift", spec.overrides))
    pred = numpyro.deterministic("shift_pred", curve + offset * data["direction"])
    observe_shift(pred, sigma, data["shift"], likelihood=spec.likelihood, df=spec.student_df)


def _baseline_curve(amp, power, amplitude, f0):
    xs = amplitude * jnp.square(2.0 * jnp.pi * jnp.abs(f0)) / materials.G_STANDARD
    return -amp * jnp.power(xs, power)


def _baseline(spec: ModelSpec, data: dict) -> None:
    mu = numpyro.sample("mu_f0", prior("mu_f0", spec.overrides))
    tau = numpyro.sample("tau_f0", prior("tau_f0", spec.overrides))
    with numpyro.plate("protocols", data["n_protocols"]):
        f0 = numpyro.sample("f0_obs", dist.Normal(mu, tau), obs=data["f0"])
    if spec.use_shift:
        amp = numpyro.sample("amp", prior("amp", spec.overrides))
        power = numpyro.sample("power", prior("power", spec.overrides))
        _observe_drive(spec, _baseline_curve(amp, power, data["amplitude"],
                                             f0[data["proto"]]), data)
    if spec.use_q:
        _nuisance_q(spec, data)


def _law_globals(spec: ModelSpec, data: dict) -> dict[str, Any]:
    """Sample the law's global parameters; returns them with log delta0_ref and the
    shape parameter of the f0 -> delta0 map."""
    law, load, radius = spec.law, data["load"], data["radius"]
    g: dict[str, Any] = {"n": None, "gamma": None, "young": None, "e_star": None, "shape": 0.0}
    if law == "powerlaw":
        g["n"] = g["shape"] = numpyro.sample("n", prior("n", spec.overrides))
        # the prefactor C is not identifiable apart from delta0_ref: sample the latter
        g["log_ref"] = numpyro.sample("delta0_ref_log", prior("delta0_ref_log", spec.overrides))
        return g
    young = g["young"] = numpyro.sample("young", prior("young", spec.overrides))
    e_star = g["e_star"] = numpyro.deterministic(
        "e_star", materials.effective_modulus(young, data["nu_bead"], young, data["nu_rod"]))
    if law == "jkr":
        gamma = g["gamma"] = g["shape"] = numpyro.sample("gamma", prior("gamma", spec.overrides))
        ref = _module("jkr").static_overlap(load, e_star=e_star, radius=radius, gamma=gamma)
    else:
        ref = hertz.static_overlap(load, e_star=e_star, radius=radius)
    g["log_ref"] = jnp.log(ref)
    return g


def _damping(spec: ModelSpec, young, data: dict):
    ve = _module("viscoelastic")
    nu = data["nu_bead"]
    if spec.eta_mode == "shared":
        eta_s = eta_q = numpyro.sample("eta", prior("eta", spec.overrides))
    else:
        eta_s = numpyro.sample("eta_shift", prior("eta_shift", spec.overrides))
        eta_q = numpyro.sample("eta_q", prior("eta_q", spec.overrides))
    return (ve.damping_constant(eta1=eta_s, eta2=eta_s, young=young, poisson=nu),
            ve.damping_constant(eta1=eta_q, eta2=eta_q, young=young, poisson=nu))


def _law_model(spec: ModelSpec, data: dict) -> None:
    law = spec.law
    scene = {"load": data["load"], "mass": data["mass"], "radius": data["radius"]}
    g = _law_globals(spec, data)
    scatter = numpyro.sample("delta0_scatter", prior("delta0_scatter", spec.overrides))
    # resonance of a contact at the reference overlap (the f0 the law predicts for the
    # nominal mount; the median of the protocols' f0 a priori)
    numpyro.deterministic("f0_pred", _invert_log_overlap(law, g["log_ref"], g["shape"], scene))
    if spec.use_f0:
        f0_dist = MeasuredF0(law, g["log_ref"], scatter, g["shape"], **scene)
        with numpyro.plate("protocols", data["n_protocols"]):
            f0 = numpyro.sample("f0_obs", f0_dist, obs=data["f0"])
    else:
        if data.get("f0") is None:
            raise ValueError("use_f0=False conditions on the measured f0: data['f0'] is needed")
        f0 = data["f0"]
    delta0 = numpyro.deterministic("delta0", jnp.exp(log_overlap(law, f0, shape=g["shape"],
                                                                 **scene)))
    omega0 = 2.0 * jnp.pi * f0

    a_shift = a_q = None
    if law == "viscoelastic":
        a_shift, a_q = _damping(spec, g["young"], data)

    if spec.use_shift:
        p = data["proto"]
        x = data["amplitude"] / delta0[p]
        kw: dict[str, Any] = {}
        if law == "viscoelastic":
            kw = {"damping_constant": a_shift, "omega": omega0[p]}
        elif law == "jkr":
            curve = shift_forward(spec, x, jkr_kw={**scene, "gamma": g["gamma"]})
        if law != "jkr":
            curve = shift_forward(spec, x, n=g["n"], **kw)
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
              "jkr": ["shift", "jkr", "jkr_table"], "baseline": []}[spec.law]
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


def curve_draws(spec: ModelSpec, idata: Any, x_grid: Any, data: dict) -> np.ndarray:
    """Noise-free Delta f/f0 of an up sweep (no down-sweep offset) on ``x_grid`` =
    delta_a/delta0 for every posterior draw: array (chains * draws, len(x_grid)).

    Through :func:`shift_forward`. Protocol-dependent inputs are taken at the median
    measured f0 of ``data`` (model inputs): omega in the paper's Eq. 25, the JKR state.
    Baseline: its amplitude scale xs = delta_a omega0^2/g is evaluated with the Hertz
    overlap from that f0 as delta0 (xs = 1.5 x when the load is the weight).
    """
    post = idata.posterior

    def draws(name):
        a = np.asarray(post[name])
        return jnp.asarray(a.reshape(-1, *a.shape[2:]))

    x = jnp.asarray(np.asarray(x_grid, float))
    f0 = float(np.median(np.asarray(data["f0"])))
    load, mass, radius = data["load"], data["mass"], data["radius"]
    law = spec.law
    if law == "baseline":
        amp_x = x * hertz.overlap_from_frequency(f0, load, mass)
        fn = jax.vmap(lambda a, b: _baseline_curve(a, b, amp_x, f0))
        return np.asarray(fn(draws("amp"), draws("power")))
    if law == "powerlaw":
        return np.asarray(jax.vmap(lambda n: shift_forward(spec, x, n=n))(draws("n")))
    if law == "jkr":
        def one(gamma):
            return shift_forward(spec, x, jkr_kw={"load": load, "radius": radius,
                                                  "gamma": gamma})

        return np.asarray(jax.vmap(one)(draws("gamma")))
    if law == "viscoelastic" and spec.rung == "paper_eq25":
        ve = _module("viscoelastic")
        eta = draws("eta" if spec.eta_mode == "shared" else "eta_shift")

        def one_ve(e, y):
            a = ve.damping_constant(eta1=e, eta2=e, young=y, poisson=data["nu_bead"])
            return shift_forward(spec, x, damping_constant=a, omega=2.0 * jnp.pi * f0)

        return np.asarray(jax.vmap(one_ve)(eta, draws("young")))
    # Hertz, viscoelastic first order / backbone: one curve, no free parameter
    n_draws = int(np.prod(np.asarray(post["sigma_shift"]).shape[:2]))
    curve = np.asarray(shift_forward(spec, x))
    return np.broadcast_to(curve, (n_draws, curve.size)).copy()
