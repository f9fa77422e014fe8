"""Quadrature rules and bracketed root solves shared by the physics modules.

* :func:`gauss_legendre`: n-point Gauss-Legendre on [a, b] (spectral for smooth integrands).
* :func:`tanh_sinh`: double-exponential rule on (0, 1) (Takahasi & Mori 1974): nodes
  cluster doubly exponentially at both ends, so algebraic endpoint singularities such as
  K ~ delta^p at the contact edge converge exponentially too.
* :func:`bisect` + :func:`polish`: a monotone bracketed root without gradient, then one
  Newton step from the stopped-gradient root, which restores the implicit-function
  derivative (d root = -(dg/dtheta)/(dg/droot)) without differentiating the iterations.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["gauss_legendre", "tanh_sinh", "bisect", "polish"]


def gauss_legendre(n: int, a: float = 0.0, b: float = 1.0) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Nodes and weights of the n-point Gauss-Legendre rule on [a, b]."""
    t, w = np.polynomial.legendre.leggauss(n)
    return jnp.asarray(a + (b - a) * (t + 1) / 2), jnp.asarray(w * (b - a) / 2)


def tanh_sinh(nodes: int, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Double-exponential nodes u in (0, 1) and weights for Int_0^1 f(u) du (step h)."""
    k = np.arange(nodes) - (nodes - 1) / 2.0
    tau = k * h
    s = 0.5 * np.pi * np.sinh(tau)
    u = 0.5 * (1.0 + np.tanh(s))
    w = 0.5 * h * 0.5 * np.pi * np.cosh(tau) / np.cosh(s) ** 2
    return u, w


def bisect(fn: Callable, lo, hi, iters: int = 64):
    """Root of fn on [lo, hi] where fn changes sign (elementwise), no gradient."""
    flo = fn(lo)

    def body(_, c):
        lo, hi, flo = c
        mid = 0.5 * (lo + hi)
        fm = fn(mid)
        same = jnp.sign(fm) == jnp.sign(flo)
        return jnp.where(same, mid, lo), jnp.where(same, hi, mid), jnp.where(same, fm, flo)

    lo, hi, _ = jax.lax.fori_loop(0, iters, body, (lo, hi, flo))
    return 0.5 * (lo + hi)


def polish(fn: Callable, root):
    """One Newton step from a converged root: restores implicit-function gradients."""
    root = jax.lax.stop_gradient(root)
    val, slope = jax.jvp(fn, (root,), (jnp.ones_like(root),))
    return root - val / slope
