"""A value taken from one of two branches, with its derivative taken from inside the branch.

Why. The folds (:mod:`inference.speed.fold`, :mod:`inference.speed.residual_fold`) choose per step
between a table (cheap) and the exact curve (costly) with ``lax.cond``. Differentiated
through, the cond makes the forward pass carry the residuals of both branches (the exact
curve's many intermediates, zeros when the table is taken) every step. Here the branches
return the value and its derivative in z themselves, and the
derivative rule contracts that with z's tangent: the cond carries nothing else.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp

__all__ = ["chosen"]


def chosen(branches: Callable[..., Any], z: jnp.ndarray, others: Any) -> jnp.ndarray:
    """``branches(z, others, slope=False)`` (the value), differentiable in z through
    ``branches(z, others, slope=True)`` = (value, derivative), the derivative's trailing
    axes those of z. ``others`` get no derivative (the branches do not depend on them)."""
    return _chosen(branches, z, others)


@partial(jax.custom_jvp, nondiff_argnums=(0,))
def _chosen(branches, z, others):
    return branches(z, others, slope=False)


@_chosen.defjvp
def _chosen_jvp(branches, primals, tangents):
    z, others = primals
    value, derivative = branches(z, others, slope=True)
    t = tangents[0]
    return value, jnp.tensordot(derivative, t, axes=jnp.ndim(t))
