"""The map from a protocol's measured linear resonance f0 to its static overlap delta0, and
the density of the measured f0 that the NumPyro models condition on.

:func:`log_overlap` is the law's f0 -> log delta0 map at the known load (models.hertz /
powerlaw / jkr ``overlap_from_frequency``); :class:`MeasuredF0` is the density

    p(f0) = Normal(log delta0(f0; theta); log delta0_ref(theta), scatter)
            * |d log delta0(f0; theta) / d f0|,

its Jacobian by forward-mode autodiff of that map. Why the models condition on f0 this way
is in :mod:`inference.numpyro_models`, which uses both and re-exports them; they live here
because they are the one part of the models that is a distribution of its own rather than
model structure.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import numpyro.distributions as dist
from numpyro.distributions import constraints
from numpyro.distributions.util import promote_shapes

from models import hertz, jkr, powerlaw

__all__ = ["log_overlap", "MeasuredF0"]


def log_overlap(law: str, f0: jnp.ndarray, *, load: float, mass: float, radius: float,
                shape: jnp.ndarray | float = 0.0) -> jnp.ndarray:
    """log delta0 [log m] implied by the measured f0 [Hz] at load F0 [N] for ``law``.

    ``shape`` is the law's shape parameter: n (power law), gamma [J/m^2] (JKR), unused
    otherwise. Elementwise in f0 (broadcasting with ``shape``).
    """
    if law in ("hertz", "viscoelastic"):
        d = hertz.overlap_from_frequency(f0, load, mass)
    elif law == "powerlaw":
        d = powerlaw.overlap_from_frequency(f0, load, mass, shape)
    elif law == "jkr":
        d = jkr.overlap_from_frequency(f0, load, mass, radius=radius, gamma=shape)
    else:
        raise ValueError(f"no overlap map for law {law!r}")
    return jnp.log(d)


def _log_overlap_and_slope(law, f0, shape, scene):
    # d log delta0 / d f0 elementwise: one forward-mode pass with unit tangents
    def fn(f):
        return log_overlap(law, f, shape=shape, **scene)

    f0 = jnp.asarray(f0, dtype=float)
    return jax.jvp(fn, (f0,), (jnp.ones_like(f0),))


def _invert_log_overlap(law, target, shape, scene, guess: float = 2700.0):
    """f0 [Hz] with log delta0(f0) = target: Newton in log f0 (exact in one step where
    delta0 ~ f0^-2, which holds for every law here; three steps guard the general case)."""
    target = jnp.asarray(target, dtype=float)
    u = jnp.full(jnp.broadcast_shapes(target.shape, jnp.shape(shape)), np.log(guess))

    def fn(uu):
        return log_overlap(law, jnp.exp(uu), shape=shape, **scene)

    for _ in range(3):
        val, slope = jax.jvp(fn, (u,), (jnp.ones_like(u),))
        u = u - (val - target) / slope
    return jnp.exp(u)


class MeasuredF0(dist.Distribution):
    """Density of the measured f0 [Hz] when delta0 = delta0(f0; theta) exactly:

        p(f0) = Normal(log delta0(f0); log_ref, scatter) |d log delta0/d f0|.

    Sampling draws log delta0 ~ Normal(log_ref, scatter) and inverts the map.
    ``law`` is static; the scene is load [N], mass [kg], radius [m].
    """

    @property
    def scene(self) -> dict[str, Any]:
        return {"load": self.load, "mass": self.mass, "radius": self.radius}

    arg_constraints = {"log_ref": constraints.real, "scatter": constraints.positive,
                       "shape": constraints.real}
    support = constraints.positive
    pytree_data_fields = ("log_ref", "scatter", "shape", "load", "mass", "radius")
    pytree_aux_fields = ("law",)

    def __init__(self, law: str, log_ref, scatter, shape=0.0, *, load: float, mass: float,
                 radius: float, validate_args=None) -> None:
        self.law = law
        # arrays, not floats: the scene may be traced (MCMC with jit_model_args)
        self.load, self.mass, self.radius = load, mass, radius
        self.log_ref, self.scatter, self.shape = promote_shapes(
            jnp.asarray(log_ref, float), jnp.asarray(scatter, float), jnp.asarray(shape, float))
        batch = jax.lax.broadcast_shapes(jnp.shape(self.log_ref), jnp.shape(self.scatter),
                                         jnp.shape(self.shape))
        super().__init__(batch_shape=batch, validate_args=validate_args)

    def sample(self, key, sample_shape=()):
        shape = sample_shape + self.batch_shape
        z = self.log_ref + self.scatter * jax.random.normal(key, shape)
        return _invert_log_overlap(self.law, z, self.shape, self.scene)

    def log_prob(self, value):
        logd, slope = _log_overlap_and_slope(self.law, value, self.shape, self.scene)
        return (dist.Normal(self.log_ref, self.scatter).log_prob(logd)
                + jnp.log(jnp.abs(slope)))
