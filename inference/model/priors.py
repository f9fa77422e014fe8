"""Priors of the contact-law models, each justified from physics.

Every prior has an inverse CDF (numpyro's nested-sampling wrapper reparameterises each
latent site to Uniform(0, 1) through it), and all are proper (evidence needs that).

- The contact laws' own parameters (``young``, ``eta``, ``n``, ``gamma``, ...) carry their
  priors, with the physical justification, in their law objects (``models/<law>.py``,
  :class:`models.law.Param`); :func:`to_distribution` turns them into NumPyro
  distributions (a LogUniform is sampled through its log: :class:`LogUniformLogit`; numpyro's
  plain LogUniform maps u through sigmoid on eta itself, where the prior mass of the
  lower decades sits at u < -10, a funnel: ESS 3 for an eta the data do not pin).
- ``delta0_scatter`` ~ HalfNormal(0.3): protocol-to-protocol scatter of log delta0
  (remounting the bead changes the contact); 0.3 in log is a 30 % overlap change,
  i.e. 15 % in f0 (delta0 ~ f0^-2 at fixed load), more than the observed ~5 % f0 scatter.
- ``sigma_shift`` ~ HalfNormal(0.01): the floor of the shift noise
  (:mod:`inference.model.shift_noise`). Delta f/f0 of the drive sweeps is at most ~0.1;
  a 1 % scatter is generous for a peak frequency (2 Hz at 2.7 kHz is 7e-4).
- ``kappa_shift`` ~ Gamma(2, 20) (mean 0.1, mode 0.05, 4 % above 0.25): the part of the
  shift noise that grows with the shift, as a fraction of it: the up/down difference of a
  bent peak and the contact's wear between steps are a tenth of the shift or so. Its
  density vanishes at 0, where a HalfNormal's does not: on data that leave it near 0
  (hertz_dynamics) a HalfNormal's boundary made NUTS's tail ESS of it 133 of 1800 draws,
  failing the gate, against 260 here.
- ``tau_shift`` ~ HalfNormal(0.005): the offset every shift of a protocol shares through
  its first reference (the reference's own peak error, 1-2 Hz, is 4-7e-4 of 2.7 kHz; a
  drift before the first drive adds to it); 0.005 (13 Hz) is generous.
- ``offset_down`` ~ Normal(0, 0.005): softening resonances peak lower in a downward
  sweep (the jump is delayed); the per-direction offset absorbs that hysteresis.
  ``offset_down`` and ``mu_f0`` are Normals sampled in (x - loc)/scale
  (:class:`inference.model.coordinates.ScaledNormal`: same prior, O(1) sampler coordinates).
- ``sigma_amp`` ~ HalfNormal(0.05), ``tau_amp`` ~ HalfNormal(0.05): the relative error of
  a sweep's resonance amplitude and of its protocol's reference amplitude
  (:mod:`inference.model.amplitude`); a vibrometer reads an amplitude to ~1 %, a peak picked
  on a frequency grid loses a few per cent more; 5 % is generous.
- ``offset_amp_down`` ~ Normal(0, 0.05): the log amplitude of down sweeps against up sweeps
  (an up sweep of a bent peak jumps before its top: its largest amplitude is lower).
- ``loss_exponent`` ~ Uniform(0, 3): the background loss of a law with none of its own
  scales as Omega^beta: 0 a constant loss factor, 1 a constant dashpot, 3 radiation into
  the rod (or any stiffness-proportional loss); the data decide between them.
- baseline ``loss_gain`` ~ Normal(0, 0.5), ``loss_power`` ~ Uniform(0.5, 4): its law-free
  ln L(x) - ln L0 = beta ln Omega + g (xs/xs_ref)^p, a change of the loss of either sign
  at the pivot amplitude of up to ~65 % (one sd).
- ``sigma_logq`` ~ HalfNormal(1): measured Q scatters by a factor of ~5 over protocols.
- ``mu_logq`` ~ Normal(log 50, 1.5), ``tau_logq`` ~ HalfNormal(1): law-free nuisance model
  of Q for the laws that predict none (keeps every model's data identical).
- baseline ``a_ref`` ~ LogNormal(log 0.02, 1.5), ``power`` ~ Uniform(0.5, 4): Delta f/f0 =
  -a_ref (xs/xs_ref)^power is any monotone power curve from square-root to quartic. The
  pivot xs_ref sits among the largest sweeps (inference.model.baseline.reference_scale), which
  approach contact loss: first-order Hertz softens by 0.05 at x = 1, so a_ref is a few
  per cent, known to a factor ~4.5 either way (95 % in [1e-3, 0.38]). Prior predictive
  medians of |Delta f/f0| on hertz_dynamics: 1.3e-4, 0.02, 0.032 at the smallest, pivot
  and largest amplitude; on paper_like 0.035 at the largest amplitude, below the largest
  shift measured (~0.13).
- baseline ``mu_f0`` ~ Normal(2700, 300) Hz, ``tau_f0`` ~ HalfNormal(200) Hz: the bead
  resonance on steel is 2.6-2.9 kHz across laws.
"""

from __future__ import annotations

import math
from typing import Any

import jax.numpy as jnp
import numpyro.distributions as dist
from numpyro.distributions import constraints, transforms
from numpyro.distributions.transforms import biject_to

from beadrod.inference.model.coordinates import ScaledNormal
from beadrod.models.law import Prior

__all__ = ["PRIORS", "prior", "LogUniformLogit", "to_distribution", "law_prior"]


class _LogInterval(constraints._Interval):
    """An interval whose unconstrained bijection goes through the log (see below)."""


@biject_to.register(_LogInterval)
def _log_interval_bijection(c: _LogInterval) -> transforms.Transform:
    lo, hi = jnp.log(c.lower_bound), jnp.log(c.upper_bound)
    return transforms.ComposeTransform([transforms.SigmoidTransform(),
                                        transforms.AffineTransform(lo, hi - lo),
                                        transforms.ExpTransform()])


class LogUniformLogit(dist.LogUniform):
    """LogUniform(low, high) whose unconstrained coordinate is logit of the log-position
    (density, icdf and support are LogUniform's; only NUTS/SMC's coordinates change)."""

    def __init__(self, low, high, *, validate_args=None) -> None:
        super().__init__(low, high, validate_args=validate_args)
        self._support = _LogInterval(self.low, self.high)

PRIORS: dict[str, dist.Distribution] = {
    "delta0_scatter": dist.HalfNormal(0.3),
    "sigma_shift": dist.HalfNormal(0.01),
    "kappa_shift": dist.Gamma(2.0, 20.0),
    "tau_shift": dist.HalfNormal(0.005),
    "offset_down": ScaledNormal(0.0, 0.005),
    "sigma_amp": dist.HalfNormal(0.05),
    "tau_amp": dist.HalfNormal(0.05),
    "offset_amp_down": ScaledNormal(0.0, 0.05),
    "loss_exponent": dist.Uniform(0.0, 3.0),
    "loss_gain": ScaledNormal(0.0, 0.5),
    "loss_power": dist.Uniform(0.5, 4.0),
    "sigma_logq": dist.HalfNormal(1.0),
    "mu_logq": dist.Normal(math.log(50.0), 1.5),
    "tau_logq": dist.HalfNormal(1.0),
    "a_ref": dist.LogNormal(math.log(0.02), 1.5),
    "power": dist.Uniform(0.5, 4.0),
    "mu_f0": ScaledNormal(2700.0, 300.0),
    "tau_f0": dist.HalfNormal(200.0),
}


def to_distribution(spec: Any) -> dist.Distribution:
    """A NumPyro distribution from a :class:`models.law.Prior` (distributions pass through)."""
    if not isinstance(spec, Prior):
        return spec
    return {"uniform": lambda: dist.Uniform(spec.a, spec.b),
            "loguniform": lambda: LogUniformLogit(spec.a, spec.b),
            "lognormal": lambda: dist.LogNormal(math.log(spec.a), spec.b),
            "normal": lambda: dist.Normal(spec.a, spec.b),
            "halfnormal": lambda: dist.HalfNormal(spec.a)}[spec.kind]()


def law_prior(param: Any, overrides: dict[str, dist.Distribution] | None = None
              ) -> dist.Distribution:
    """The prior of a law parameter (:class:`models.law.Param`); ``overrides`` wins."""
    if overrides and param.name in overrides:
        return overrides[param.name]
    return to_distribution(param.prior)


def prior(name: str, overrides: dict[str, dist.Distribution] | None = None) -> dist.Distribution:
    """The prior of parameter ``name`` (``overrides`` wins): a nuisance parameter of
    :data:`PRIORS`, else the first registered law parameter of that name; KeyError if
    unknown."""
    if overrides and name in overrides:
        return overrides[name]
    if name in PRIORS:
        return PRIORS[name]
    from beadrod.models.registry import laws

    for law in laws():
        if name in law.param_names:
            return to_distribution(law.param(name).prior)
    raise KeyError(name)
