"""NumPyro models of the bead-rod data, one per contact law, built from ``models/`` only.

Structure shared by every law (names are the sample sites):

* The law is a :class:`models.law.ContactLaw` from :mod:`models.registry` (built in or
  from a user's law file): its parameters are sampled from its own priors
  (:func:`inference.model.priors.law_prior`), its functions get the resolved keywords (law
  parameters and scene quantities). No code here branches on a law's name.
* The static overlap of each protocol is fixed by its measured linear resonance f0_p:
  at the known load F0 (the bead's weight) the law's tangent stiffness gives
  ``delta0_p = delta0(f0_p; theta)`` (models.laws.hertz / powerlaw / jkr
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
* Reference Q where the protocol has one: a law with a loss channel (the viscoelastic
  law: Q_p = 1/(omega0_p A(eta, E))) predicts Q_p at the measured omega0_p = 2 pi f0_p and
  ``q_obs ~ LogNormal(log Q_p, sigma_logq)``; laws that predict no Q get a law-free
  nuisance model log Q ~ Normal(mu_logq, tau_logq), so every model describes the same
  data and evidences are comparable.

Rungs (``ModelSpec.rung``, one of models.registry.FIT_RUNGS): the law computes its own
shift at the rung (:meth:`models.law.ContactLaw.shift`): a closed form or a table where it
has one (Hertz, power law, viscoelastic, JKR and DMT have fast paths at every rung they
list: 'first_order', 'backbone', and for the viscoelastic law the paper's 'paper_eq25'),
else the generic quadrature of models.ladder.generic (exact, slow). A law without the rung is
refused (:class:`ForwardModelUnavailable`), never swapped for another rung. A fast path
with a limited domain (a table's x <= 2 and shape range; the rough sphere's summits in
contact: the law's ``domains``) holds its end value outside it, which is not the law's
curve: a parameter point that puts any sweep outside gets zero likelihood (site
``law_domain``), so no sampler and no evidence counts a held value. In effect the prior
is truncated to the domain, and log Z counts only the mass inside it.

The fold (``ModelSpec.fold``, on by default): where the law's whole sweep curve depends on
one of its parameters (JKR, DMT: gamma; the power law: n; the rough sphere: its roughness
factor), the curve is tabulated once along that parameter before sampling and each step
reads one cell of it (:mod:`inference.speed.fold`: the exact curve to 1e-7 where it is used,
checked where it is built; elsewhere the exact curve). Where the f0 -> delta0 map and its
Jacobian depend on the same one parameter (all four), they are folded with the curve
(:mod:`inference.speed.steps`). The likelihood is unchanged to that tolerance, and a step reads
one cell per sweep point instead of the law's tables.
Where the curve depends on two parameters (Maugis-Dugdale: gamma and lambda) and the
sweeps' likelihood is Normal, that likelihood is folded instead: it reads the curve
through two residual sums, tabulated in the two parameters over the region the data leave
plausible (:mod:`inference.speed.residual_fold`: within 1e-3 nat of the exact log-likelihood
where used, checked where built; elsewhere exact). The point-wise likelihood (LOO) and
the predictive draws evaluate the curve exactly (``data[POINTWISE]``).

The law-free ``baseline``: Delta f/f0 = -amp * xs^power with xs = delta_a omega0_p^2 / g
(the overlap scale g/omega0^2 of a linear spring; any other scale is absorbed into amp),
f0_obs ~ Normal(mu_f0, tau_f0), the nuisance Q model. It fits any smooth monotone
softening: a law that loses to it is missing the data's shape.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import numpyro
import numpyro.distributions as dist

from beadrod.inference.model.amplitude import has_amplitudes, observe_amplitude, predicted_ratio
from beadrod.inference.model.baseline import (
    baseline_curve,
    baseline_model,
    nuisance_q,
    observe_drive,
)
from beadrod.inference.model.likelihood import observe_logq
from beadrod.inference.model.overlap import MeasuredF0, invert_log_overlap, log_overlap
from beadrod.inference.model.priors import law_prior, prior
from beadrod.inference.model.shift_noise import DEFAULT_SHIFT_NOISE, SHIFT_NOISES
from beadrod.inference.speed.residual_fold import POINTWISE, ResidualFold, sums
from beadrod.inference.speed.steps import StepFold, SweepCurve, step_fold
from beadrod.models.law import RungUnavailable, sampler_site
from beadrod.models.laws import hertz
from beadrod.models.registry import FIT_RUNGS, get_law, law_names

__all__ = ["RUNGS", "BASELINE", "ModelSpec", "ForwardModelUnavailable",
           "build_model", "paper_spec", "model_names", "MeasuredF0", "log_overlap",
           "curve_draws", "law_of", "SweepCurve", "StepFold", "step_fold"]

BASELINE = "baseline"
"""The law-free model's name (not a contact law: it has no force)."""
RUNGS = FIT_RUNGS


def model_names() -> tuple[str, ...]:
    """Every model the comparison can fit: the registered laws, then the baseline."""
    return (*law_names(), BASELINE)


class ForwardModelUnavailable(RungUnavailable):
    """The requested rung's forward function is not available for this law."""


@dataclass(frozen=True)
class ModelSpec:
    """What to build: a registered law (or the baseline) at a rung.

    ``eta_mode='split'`` with ``law='viscoelastic'`` is the law ``viscoelastic_split``
    (another spelling of it). ``f0_sd`` [Hz] is the measurement noise of f0 that the
    exact conditioning on f0 neglects (documented, not used by the likelihood);
    ``use_f0=False`` conditions on the measured f0 without its density (evidences are
    then not comparable). ``fold=False`` evaluates the law's sweep curve directly at every
    step instead of through its fold in the one parameter it depends on (inference.speed.fold;
    the same curve to 1e-7, checked where it is built).
    """

    law: str = "hertz"
    rung: str = "first_order"
    eta_mode: str = "shared"
    use_shift: bool = True
    use_q: bool = True
    use_f0: bool = True
    use_amplitude: bool = True
    likelihood: str = "normal"
    student_df: float = 4.0
    shift_noise: str = DEFAULT_SHIFT_NOISE
    f0_sd: float = 5.0
    fold: bool = True
    overrides: dict[str, Any] = field(default_factory=dict, hash=False, compare=False)

    def __post_init__(self) -> None:
        if self.eta_mode not in ("shared", "split"):
            raise ValueError("eta_mode must be 'shared' or 'split'")
        if self.eta_mode == "split":
            if self.law != "viscoelastic":
                raise ValueError("eta_mode 'split' exists only for the viscoelastic law")
            object.__setattr__(self, "law", "viscoelastic_split")
        if self.law == "viscoelastic_split":
            object.__setattr__(self, "eta_mode", "split")
        if self.law not in model_names():
            raise ValueError(f"unknown law {self.law!r}; choose from {list(model_names())}")
        if self.rung not in RUNGS:
            raise ValueError(f"unknown rung {self.rung!r}; choose from {list(RUNGS)}")
        if self.law != BASELINE and self.rung not in get_law(self.law).physics.rungs:
            raise ForwardModelUnavailable(
                f"law '{self.law}' cannot be fitted at rung '{self.rung}': its rungs are "
                f"{list(get_law(self.law).physics.rungs)}")
        if self.likelihood not in ("normal", "student_t"):
            raise ValueError("likelihood must be 'normal' or 'student_t'")
        if self.shift_noise not in SHIFT_NOISES:
            raise ValueError(f"shift_noise must be one of {list(SHIFT_NOISES)}, got "
                             f"{self.shift_noise!r}")

    @property
    def name(self) -> str:
        parts = [self.law]
        if self.law != BASELINE:
            parts.append(self.rung)
        if self.likelihood != "normal":
            parts.append(self.likelihood)
        if self.shift_noise != DEFAULT_SHIFT_NOISE:
            parts.append(f"{self.shift_noise}-noise")
        if not self.use_shift:
            parts.append("no-shift")
        if not self.use_q:
            parts.append("no-q")
        if not self.use_f0:
            parts.append("no-f0")
        if not self.use_amplitude:
            parts.append("no-amplitude")
        return "/".join(parts)


def law_of(spec: ModelSpec):
    """The spec's law object (None for the baseline)."""
    return None if spec.law == BASELINE else get_law(spec.law)


def paper_spec(law: str, **kw: Any) -> ModelSpec:
    """The paper's own formulas (rung 'paper_eq25' where the law has it, else first order)."""
    rung = "paper_eq25" if "paper_eq25" in get_law(law).physics.rungs else "first_order"
    return ModelSpec(law=law, rung=rung, **kw)


def _theta(law, spec: ModelSpec) -> dict[str, Any]:
    # the parameters without a sampler scale first: a scale is a function of them
    free = {p.name: numpyro.sample(p.name, law_prior(p, spec.overrides))
            for p in law.params if p.name not in law.sampler.scales}
    theta = dict(free)
    for p in law.params:
        scale = law.sampler.scales.get(p.name)
        if scale is not None:
            # p s ~ the law's prior of p scaled by s (a change of variables: p keeps its
            # prior); the sampler's coordinate is that of p s (models.law.SamplerHints)
            s = scale(**free)
            base = law_prior(p, spec.overrides)
            # the transform's domain is the prior's support, so that the scaled site's
            # support is its image (p > 0: p s > 0, unconstrained as ln(p s)); the default
            # domain, the real line, would let the sampler move p s through zero
            scaled = numpyro.sample(sampler_site(p.name), dist.TransformedDistribution(
                base, dist.transforms.AffineTransform(0.0, s, domain=base.support)))
            theta[p.name] = numpyro.deterministic(p.name, scaled / s)
    return {p.name: theta[p.name] for p in law.params}


def _law_model(spec: ModelSpec, data: dict) -> None:
    law = law_of(spec)
    theta = _theta(law, spec)
    kw = law.resolve(data["scene"], theta)
    if "e_star" in kw and "e_star" not in law.param_names and "young" in law.param_names:
        numpyro.deterministic("e_star", kw["e_star"])
    log_ref = jnp.log(law.overlap(**kw))
    scatter = numpyro.sample("delta0_scatter", prior("delta0_scatter", spec.overrides))
    # the resonance of a contact at the reference overlap (the median f0 a priori)
    numpyro.deterministic("f0_pred", invert_log_overlap(law.name, log_ref, kw))
    observed = data.get("f0")
    folded: dict[str, Any] = {}
    residual: ResidualFold | None = None
    steps = None
    if observed is not None and (spec.fold or spec.use_shift):
        steps = SweepCurve(law, spec, data, observed)
        fold = step_fold(steps, data) if spec.fold else None
        if isinstance(fold, ResidualFold):
            # the sweeps' likelihood folded (point-wise, the model evaluates the curve)
            residual = None if data.get(POINTWISE) else fold
        else:
            folded = {} if fold is None else fold.values(steps, theta)
    known = (observed, folded["log_delta0"], folded["log_slope"]) if "log_slope" in folded \
        else None
    if spec.use_f0:
        with numpyro.plate("protocols", data["n_protocols"]):
            f0 = numpyro.sample("f0_obs", MeasuredF0(law.name, log_ref, scatter, kw,
                                                     known=known), obs=observed)
    else:
        if observed is None:
            raise ValueError("use_f0=False conditions on the measured f0: data['f0'] is needed")
        f0 = observed
    log_d0 = known[1] if known is not None else log_overlap(law.name, f0, kw)
    delta0 = numpyro.deterministic("delta0", jnp.exp(log_d0))
    omega0 = 2.0 * jnp.pi * f0
    if spec.use_shift:
        # the sweeps on a (protocol, slot) grid (inference.model.likelihood.sweep_layout): every
        # protocol quantity enters as a (P, 1) column
        sweeps = steps if steps is not None else SweepCurve(law, spec, data, f0)
        x, per = sweeps.grid(kw, delta0)
        curve = folded["curve"] if "curve" in folded else sweeps.curve(x, per)
        inside = sweeps.inside(x, per)
        if inside is not None:
            # outside its domain the fast path holds a value that is not the law's: such
            # a point gets zero likelihood rather than a silently wrong one (the prior
            # is in effect truncated to the domain; log Z counts only the mass inside)
            numpyro.factor("law_domain", jnp.where(inside, 0.0, -jnp.inf))
        observe_drive(spec, curve, data, None if residual is None
                      else sums(residual, theta, steps.residual_sums))
    # the law's Q: its density where Q is observed, its linear loss for the amplitudes
    q_pred = (numpyro.deterministic("q_pred", law.quality_factor(omega0=omega0, **kw))
              if law.predicts_q and (spec.use_q or spec.use_amplitude) else None)
    if spec.use_q:
        if q_pred is not None:
            sigma = numpyro.sample("sigma_logq", prior("sigma_logq", spec.overrides))
            observe_logq(jnp.log(q_pred[data["q_idx"]]), sigma, data["q_obs"],
                         likelihood=spec.likelihood, df=spec.student_df)
        else:
            nuisance_q(spec, data)
    if spec.use_shift and spec.use_amplitude and has_amplitudes(data):
        _law_amplitude(spec, law, kw, curve, delta0, q_pred, data)


def _law_amplitude(spec: ModelSpec, law: Any, kw: dict, curve: jnp.ndarray,
                   delta0: jnp.ndarray, q_pred: jnp.ndarray | None, data: dict) -> None:
    """The amplitude ratios under the law's loss (inference.model.amplitude): its own
    linear loss 1/Q where it predicts Q, else the measured one; its own loss exponent, else
    the fitted background's."""
    idx, p_i = data["amp_idx"], data["amp_proto"]
    beta = (law.physics.loss_exponent if law.has_own_loss
            else numpyro.sample("loss_exponent", prior("loss_exponent", spec.overrides)))
    linear = 1.0 / (q_pred if q_pred is not None else data["q_plugin"])
    x = data["amplitude"][idx] / delta0[p_i]
    # the resonance ratio at the sweep's amplitude: the up-sweep curve (a bound keeps the
    # log finite at parameter points far outside what any data allow)
    omega = jnp.maximum(1.0 + curve[idx], 1e-3)
    loss = law.loss(x, linear_loss=linear[p_i], omega_ratio=omega,
                    background_exponent=beta, **kw)
    x_ref = data["ref_amplitude"] / delta0
    loss_ref = law.loss(x_ref, linear_loss=linear, omega_ratio=1.0,
                        background_exponent=beta, **kw)[p_i]
    observe_amplitude(spec, predicted_ratio(omega_ratio=omega, loss=loss, loss_ref=loss_ref),
                      data)


def _probe(spec: ModelSpec, data_scene: dict | None) -> None:
    """Finite values and x-gradients of the law's shift at the prior medians, where NUTS
    goes (inside and beyond contact loss); else ForwardModelUnavailable. Only for fast
    paths: the generic quadrature is exact by construction and costly to compile."""
    law = law_of(spec)
    if law is None or spec.rung not in law.physics.shifts or data_scene is None:
        return
    theta = {p.name: p.prior.median() if hasattr(p.prior, "median")
             else float(p.prior.icdf(0.5)) for p in law.params}
    kw = law.resolve(data_scene, theta)
    d0 = law.overlap(**kw)
    x = jnp.array([0.05, 0.5, 0.95, 1.3])

    def total(xx):
        return jnp.sum(law.shift(xx, rung=spec.rung, delta0=d0, omega0=2 * jnp.pi * 2700.0,
                                 **kw))

    val, grad = jax.value_and_grad(total)(x)
    if not (jnp.isfinite(val) and jnp.all(jnp.isfinite(grad))):
        raise ForwardModelUnavailable(
            f"law '{law.name}' at rung '{spec.rung}' is not finite/differentiable at its "
            f"prior medians: sum {val}, d/dx {grad}")


def build_model(spec: ModelSpec | str, n_protocols: int | None = None,
                scene: dict | None = None, **kw: Any) -> Callable[..., None]:
    """NumPyro model ``model(data)`` for ``spec`` (a ModelSpec or a law name + kwargs).

    ``data`` is :func:`inference.model.likelihood.model_inputs` (observations under ``f0``,
    ``shift``, ``q_obs``; None entries are simulated: prior/posterior predictive).
    ``n_protocols`` is taken from ``data['f0']`` when observed; give it for prior
    predictive runs without f0. ``scene`` (scene quantities) enables a probe of the
    forward model before sampling.
    """
    if isinstance(spec, str):
        spec = ModelSpec(law=spec, **kw)
    elif kw:
        spec = replace(spec, **kw)
    _probe(spec, scene)

    def model(data: dict) -> None:
        data = dict(data)
        if "n_protocols" not in data:
            if data.get("f0") is not None:
                data["n_protocols"] = data["f0"].shape[0]
            elif n_protocols is not None:
                data["n_protocols"] = n_protocols
            else:
                raise ValueError("n_protocols is needed when f0 is not observed")
        if spec.law == BASELINE:
            baseline_model(spec, data)
        else:
            _law_model(spec, data)

    model.spec = spec  # type: ignore[attr-defined]
    return model


def curve_draws(spec: ModelSpec, idata: Any, x_grid: Any, data: dict) -> np.ndarray:
    """Noise-free Delta f/f0 of an up sweep (no down-sweep offset) on ``x_grid`` =
    delta_a/delta0 for every posterior draw: array (chains * draws, len(x_grid)).

    Protocol-dependent inputs are taken at the median measured f0 of ``data`` (model
    inputs): delta0 and omega0 there. Baseline: its amplitude scale xs = delta_a omega0^2/g
    is evaluated with the Hertz overlap from that f0 as delta0 (xs = 1.5 x when the load
    is the weight).
    """
    post = idata.posterior

    def draws(name):
        a = np.asarray(post[name])
        return jnp.asarray(a.reshape(-1, *a.shape[2:]))

    x = jnp.asarray(np.asarray(x_grid, float))
    f0 = float(np.median(np.asarray(data["f0"])))
    law = law_of(spec)
    if law is None:
        amp_x = x * hertz.overlap_from_frequency(f0, data["load"], data["mass"])
        fn = jax.vmap(lambda a, b: baseline_curve(a, b, amp_x, f0))
        return np.asarray(fn(draws("amp"), draws("power")))
    n_draws = int(np.prod(np.asarray(post["sigma_shift"]).shape[:2]))
    theta = {p: draws(p) for p in law.param_names}

    def one(th):
        kw = law.resolve(data["scene"], th)
        d0 = law.overlap_at(jnp.asarray(f0), **kw)
        return law.shift(x, rung=spec.rung, delta0=d0, omega0=2.0 * jnp.pi * f0, **kw)

    if not theta:
        curve = np.asarray(one({}))
        return np.broadcast_to(curve, (n_draws, curve.size)).copy()
    return np.asarray(jax.lax.map(one, theta, batch_size=256))
