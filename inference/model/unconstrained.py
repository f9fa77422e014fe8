"""Draws of a numpyro model's latent sites as flat vectors in its unconstrained space.

Mode search and bridge sampling both work on numpyro's unconstrained space as one flat
vector per draw. :func:`flatten_unconstrained` is meant to run inside their compiled
programs, so that the model's transforms are traced there once rather than once more
outside them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
import jax.flatten_util
import jax.numpy as jnp
from numpyro.infer.util import unconstrain_fn

__all__ = ["flatten_unconstrained"]


def flatten_unconstrained(model: Callable, model_kwargs: dict, draws: dict[str, Any]
                          ) -> tuple[jnp.ndarray, Callable]:
    """(flat, unravel): ``draws`` (each site's constrained values with a leading draw axis)
    mapped to the unconstrained space, one row per draw, and the function that maps one
    row back to a dict of unconstrained site values. ``unravel`` holds only the layout
    (shapes, dtypes), so it may be used outside the ``jit`` it was made in."""
    u = jax.vmap(lambda p: unconstrain_fn(model, (), model_kwargs, p))(draws)
    _, unravel = jax.flatten_util.ravel_pytree(jax.tree_util.tree_map(lambda a: a[0], u))
    return jax.vmap(lambda t: jax.flatten_util.ravel_pytree(t)[0])(u), unravel
