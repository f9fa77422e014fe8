"""The map from a protocol's measured linear resonance f0 to its static overlap delta0, and
the density of the measured f0 that the NumPyro models condition on.

:func:`log_overlap` is the law's f0 -> log delta0 map at the known load
(:meth:`models.law.ContactLaw.overlap_at`: a closed form where the law has one, else the
generic root solve of F/F' = F0/(m omega0^2)); :class:`MeasuredF0` is the density

    p(f0) = Normal(log delta0(f0; theta); log delta0_ref(theta), scatter)
            * |d log delta0(f0; theta) / d f0|,

its Jacobian by forward-mode autodiff of that map. Why the models condition on f0 this way
is in :mod:`inference.model.numpyro_models`.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpyro.distributions as dist
from numpyro.distributions import constraints
from numpyro.distributions.util import promote_shapes

from beadrod.models.registry import get_law

__all__ = ["log_overlap", "log_overlap_and_slope", "invert_log_overlap", "MeasuredF0"]


def log_overlap(law: str, f0: jnp.ndarray, kw: dict[str, Any]) -> jnp.ndarray:
    """log delta0 [log m] implied by the measured f0 [Hz] for ``law`` with resolved
    keywords ``kw`` (law parameters and scene quantities). Elementwise in f0."""
    return jnp.log(get_law(law).overlap_at(f0, **kw))


def log_overlap_and_slope(law: str, f0: jnp.ndarray,
                          kw: dict[str, Any]) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(log delta0, log |d log delta0 / d f0| [log(1/Hz)]) at the measured f0 [Hz],
    elementwise: one forward-mode pass with unit tangents."""
    f0 = jnp.asarray(f0, dtype=float)
    logd, slope = jax.jvp(lambda f: log_overlap(law, f, kw), (f0,), (jnp.ones_like(f0),))
    return logd, jnp.log(jnp.abs(slope))


def invert_log_overlap(law: str, target: Any, kw: dict[str, Any]) -> jnp.ndarray:
    """f0 [Hz] with log delta0(f0) = target: the law's inverse map
    (:meth:`models.law.ContactLaw.frequency_at`; closed form for every built-in law but
    the JKR family, a Newton solve there)."""
    return get_law(law).frequency_at(jnp.exp(jnp.asarray(target, dtype=float)), **kw)


class MeasuredF0(dist.Distribution):
    """Density of the measured f0 [Hz] when delta0 = delta0(f0; theta) exactly:

        p(f0) = Normal(log delta0(f0); log_ref, scatter) |d log delta0/d f0|.

    Sampling draws log delta0 ~ Normal(log_ref, scatter) and inverts the map. ``law`` is
    a registry name (static); ``kw`` the resolved keywords (law parameters, scene).
    ``known = (f0, log delta0, log |d log delta0/d f0|)``: the map already evaluated at
    the observed f0 (by the model's fold, :mod:`inference.speed.steps`); ``log_prob`` uses it
    when its value is that f0, and evaluates the map otherwise.
    """

    arg_constraints = {"log_ref": constraints.real, "scatter": constraints.positive}
    support = constraints.positive
    pytree_data_fields = ("log_ref", "scatter", "kw", "known")
    pytree_aux_fields = ("law",)

    def __init__(self, law: str, log_ref, scatter, kw: dict[str, Any], *,
                 known: tuple | None = None, validate_args=None) -> None:
        self.law = law
        self.kw = dict(kw)
        self.known = known
        self.log_ref, self.scatter = promote_shapes(jnp.asarray(log_ref, float),
                                                    jnp.asarray(scatter, float))
        batch = jax.lax.broadcast_shapes(jnp.shape(self.log_ref), jnp.shape(self.scatter))
        super().__init__(batch_shape=batch, validate_args=validate_args)

    def sample(self, key, sample_shape=()):
        shape = sample_shape + self.batch_shape
        z = self.log_ref + self.scatter * jax.random.normal(key, shape)
        return invert_log_overlap(self.law, z, self.kw)

    def log_prob(self, value):
        def evaluated(v):
            logd, log_slope = log_overlap_and_slope(self.law, v, self.kw)
            return jnp.broadcast_to(logd, jnp.shape(v)), jnp.broadcast_to(log_slope,
                                                                         jnp.shape(v))

        if self.known is None or jnp.shape(value) != jnp.shape(self.known[0]):
            logd, log_slope = evaluated(value)
        else:
            f0, logd, log_slope = self.known
            logd, log_slope = jax.lax.cond(jnp.all(value == f0), lambda v: (logd, log_slope),
                                           evaluated, value)
        return dist.Normal(self.log_ref, self.scatter).log_prob(logd) + log_slope
