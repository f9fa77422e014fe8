"""Hertz contact written from scratch, as a user would: the law-file contract's example.

F = (4/3) E* R^(1/2) delta^(3/2) for delta > 0, 0 otherwise (Johnson 1985, Sec. 4.2), with
E* = E / (2 (1 - nu^2)) for identical bead and rod.
"""

import jax.numpy as jnp
import numpyro.distributions as dist

NAME = "hertz_scratch"
LABEL = "Hertz (from a law file)"
REFERENCE = "Johnson 1985, Sec. 4.2"
PRIORS = {"young": dist.Uniform(150e9, 250e9)}


def force(delta, *, young, poisson, radius):
    e_star = young / (2.0 * (1.0 - poisson**2))
    touching = delta > 0
    d = jnp.where(touching, delta, 1.0)      # double where: finite gradients at delta <= 0
    return jnp.where(touching, 4.0 / 3.0 * e_star * jnp.sqrt(radius) * d**1.5, 0.0)
