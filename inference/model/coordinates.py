"""Sampler coordinates: priors whose unconstrained coordinate is standardised.

NUTS (and the tempered SMC) move in the unconstrained space that numpyro's ``biject_to``
gives each prior's support; for a Normal on the real line that is the value itself, in
its own units. The dense mass matrix is adapted with Stan's regularisation, (n/(n + 5))
Sigma + 1e-3 (5/(n + 5)) I over a window of n draws: a coordinate whose posterior sd is
far below sqrt(1e-3 * 5/205) = 5e-3 (the last window of a 500-draw warmup) is given a
mass-matrix scale of ~5e-3 instead, and the step size shrinks to match it. The down-sweep
offset [-] has a posterior sd of 4e-5 on hertz_dynamics, which costs a step size of 0.005
and ~800 leapfrog steps per draw; a mean resonance in Hz (posterior sd 30 Hz) is the
opposite case, and the adaptation, started at the identity, never reaches it (R-hat 1.06,
bulk ESS 55 on hertz_dynamics).

:class:`ScaledNormal` is Normal(loc, scale) in every respect (density, icdf for nested
sampling, support, samples) except that its unconstrained coordinate is z = (x - loc) /
scale, so a prior scale chosen from physics puts the coordinate at O(1). The Jacobian of
that map is the constant log(scale): evidences are unchanged.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpyro.distributions as dist
from numpyro.distributions import constraints, transforms
from numpyro.distributions.transforms import biject_to

__all__ = ["ScaledNormal"]


class _ScaledReal(constraints.Constraint):
    """The real line, carrying the affine map to its standardised coordinate."""

    def __init__(self, loc, scale) -> None:
        self.loc = loc
        self.scale = scale

    def __call__(self, x):
        return constraints.real(x)

    def feasible_like(self, prototype):
        return jnp.broadcast_to(self.loc, jnp.shape(prototype))

    def tree_flatten(self):
        return (self.loc, self.scale), (("loc", "scale"), {})

    def eq(self, other: object, static: bool = False):
        return (isinstance(other, _ScaledReal) and other.loc is self.loc
                and other.scale is self.scale)


@biject_to.register(_ScaledReal)
def _scaled_real_bijection(c: _ScaledReal) -> transforms.Transform:
    return transforms.AffineTransform(c.loc, c.scale)


class ScaledNormal(dist.Normal):
    """Normal(loc, scale) sampled in z = (x - loc)/scale (see the module docstring)."""

    @constraints.dependent_property(is_discrete=False, event_dim=0)
    def support(self) -> constraints.Constraint:
        return _ScaledReal(self.loc, self.scale)
