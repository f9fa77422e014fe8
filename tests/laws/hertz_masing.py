"""Hertz contact with a loss of its own, written as a user would: the law-file contract's
example of ``LOSS_EXPONENT`` and ``loss_increment``.

The force is Hertz's (as ``hertz_scratch.py``); the loss is the file's: a linear loss that
scales with the resonance as Omega^1 (a constant dashpot), plus a Masing-like increment
Delta(1/Q) = h x^(m-1) at the amplitude x = delta_a/delta0. The increment changes only
the loss: the shift comes from the force alone.
"""

import jax.numpy as jnp
import numpyro.distributions as dist

NAME = "hertz_masing"
LABEL = "Hertz + Masing-like loss (from a law file)"
REFERENCE = "Johnson 1985, Sec. 4.2 and 7.4"
PRIORS = {"young": dist.Uniform(150e9, 250e9),
          "h": dist.HalfNormal(0.01),            # Delta(1/Q) at x = 1
          "m": dist.Uniform(1.2, 3.0)}           # loss per cycle ~ x^(m+1)
LOSS_EXPONENT = 1.0                              # L0 Omega^1; leave out to fit beta


def force(delta, *, young, poisson, radius):
    e_star = young / (2.0 * (1.0 - poisson**2))
    touching = delta > 0
    d = jnp.where(touching, delta, 1.0)      # double where: finite gradients at delta <= 0
    return jnp.where(touching, 4.0 / 3.0 * e_star * jnp.sqrt(radius) * d**1.5, 0.0)


def loss_increment(x, *, h, m):
    moving = x > 0
    xs = jnp.where(moving, x, 1.0)           # double where: finite gradients at x = 0
    return jnp.where(moving, h * xs ** (m - 1.0), 0.0)
