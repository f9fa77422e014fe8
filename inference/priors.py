"""Priors of the contact-law models, each justified from physics.

Every prior has an inverse CDF (numpyro's nested-sampling wrapper reparameterises each
latent site to Uniform(0, 1) through it), and all are proper (evidence needs that).

- ``young`` E ~ Uniform(150, 250) GPa: austenitic/martensitic stainless and carbon
  steels span roughly 180-215 GPa (paper: 190-210 GPa); the wider band leaves room for
  near-surface damage and grade uncertainty without admitting non-steels.
- ``eta`` ~ LogUniform(1e2, 1e8) Pa s: the viscosity is unknown over decades. The
  paper's shift fit gives 1.05e6 Pa s, its measured Q = 20-100 implies 5e4-3e5 Pa s;
  the interval brackets both by more than two decades either way (scale-invariant).
  Sampled through its log: :class:`LogUniformLogit` maps the unconstrained value u to
  eta = exp(log lo + (log hi - log lo) sigmoid(u)), so u is logistic a priori. numpyro's
  plain LogUniform maps u through sigmoid on eta itself, where the prior mass of the
  lower decades sits at u < -10 (a funnel: ESS 3 for an eta the data do not pin).
- ``n`` ~ Uniform(1, 3): F = C delta^n with n = (1 + H)/H for Hurst exponent
  0.5 <= H < inf; n = 3/2 is Hertz, n = 2 a soft oxide shell; n < 1 would be a
  softening contact under compression, n > 3 is beyond any self-affine surface.
- ``gamma`` ~ LogNormal(log 0.7, 0.5) J/m^2: clean steel-steel surface energy is of
  order 1 J/m^2, contaminated surfaces (air, oxide) a few tenths; the paper uses 0.7.
- ``delta0_ref_log`` (power law only, where the prefactor C is unidentifiable):
  Normal(log 55 nm, 1): the Hertz overlap under the bead's weight is 50-55 nm; a
  rough or coated contact sits within a factor of e of it.
- ``delta0_scatter`` ~ HalfNormal(0.3): protocol-to-protocol scatter of log delta0
  (remounting the bead changes the contact); 0.3 in log is a 30 % overlap change,
  i.e. 15 % in f0 (delta0 ~ f0^-2 at fixed load), more than the observed ~5 % f0 scatter.
- ``sigma_shift`` ~ HalfNormal(0.01): Delta f/f0 of the drive sweeps is at most ~0.1;
  a 1 % scatter is generous for a peak frequency.
- ``offset_down`` ~ Normal(0, 0.005): softening resonances peak lower in a downward
  sweep (the jump is delayed); the per-direction offset absorbs that hysteresis.
- ``sigma_logq`` ~ HalfNormal(1): measured Q scatters by a factor of ~5 over protocols.
- ``mu_logq`` ~ Normal(log 50, 1.5), ``tau_logq`` ~ HalfNormal(1): law-free nuisance model
  of Q for the laws that predict none (keeps every model's data identical).
- baseline ``amp`` ~ HalfNormal(0.2), ``power`` ~ Uniform(0.5, 4): Delta f/f0 = -a x^b is
  any monotone power curve from square-root to quartic.
- baseline ``mu_f0`` ~ Normal(2700, 300) Hz, ``tau_f0`` ~ HalfNormal(200) Hz: the bead
  resonance on steel is 2.6-2.9 kHz across laws.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpyro.distributions as dist
from numpyro.distributions import constraints, transforms
from numpyro.distributions.transforms import biject_to

__all__ = ["PRIORS", "prior", "LogUniformLogit"]


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
    "young": dist.Uniform(150e9, 250e9),
    "eta": LogUniformLogit(1e2, 1e8),
    "eta_shift": LogUniformLogit(1e2, 1e8),
    "eta_q": LogUniformLogit(1e2, 1e8),
    "n": dist.Uniform(1.0, 3.0),
    "gamma": dist.LogNormal(math.log(0.7), 0.5),
    "delta0_ref_log": dist.Normal(math.log(55e-9), 1.0),
    "delta0_scatter": dist.HalfNormal(0.3),
    "sigma_shift": dist.HalfNormal(0.01),
    "offset_down": dist.Normal(0.0, 0.005),
    "sigma_logq": dist.HalfNormal(1.0),
    "mu_logq": dist.Normal(math.log(50.0), 1.5),
    "tau_logq": dist.HalfNormal(1.0),
    "amp": dist.HalfNormal(0.2),
    "power": dist.Uniform(0.5, 4.0),
    "mu_f0": dist.Normal(2700.0, 300.0),
    "tau_f0": dist.HalfNormal(200.0),
}


def prior(name: str, overrides: dict[str, dist.Distribution] | None = None) -> dist.Distribution:
    """The prior of parameter ``name`` (``overrides`` wins), KeyError if unknown."""
    if overrides and name in overrides:
        return overrides[name]
    return PRIORS[name]
