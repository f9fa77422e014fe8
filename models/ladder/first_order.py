"""First-order (averaged tangent stiffness) resonance shift, paper Eqs. (22)-(23), (26)-(27).

With delta = delta0 + delta_a sin t and x = delta_a/delta0, Merkel et al.
(J. Sound Vib. 441 (2019) 84, Sec. 5) estimate the resonance of the bead on the
contact spring from the tangent stiffness averaged over one period,

    omega^2 ~ <K_N(delta0 + delta_a sin t)>/m,
    Delta f/f0 ~ <K_N>/(2 K0) - 1/2                                       (Eq. 22)

(the linearised square root, "first order"); the paper's Fig. 4 also shows the
same average without that linearisation, sqrt(<K_N>/K0) - 1
(:func:`without_first_order`). For F = C delta^n, K_N = n C delta^(n-1) (Eq. 26):

    Delta f/f0 = (1/4 pi) Int_0^2pi (1 + x sin t)^(n-1) dt - 1/2          (Eq. 27)
               = 2F1((1-n)/2, (2-n)/2; 1; x^2)/2 - 1/2,

n = 3/2 being Hertz (Eq. 23). For x > 1 the bead leaves the rod during part of
the cycle: the force, hence the tangent stiffness, is zero where delta <= 0,
and the clipped mean <max(1 + x sin t, 0)^(n-1)> is used (models/ladder/hypergeometric.py).
This is still the averaged-stiffness estimate, not the free-flight dynamics;
the exact backbone is models/ladder/backbone.py.

Units: every shift is the dimensionless Delta f/f0 [-]; x [-].
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.ladder.hypergeometric import NEG_INF_GRAD, mean_power_at_one, mean_power_clipped
from beadrod.models.ladder.quadrature import tanh_sinh

__all__ = [
    "first_order_adhesive",
    "first_order_powerlaw",
    "first_order_hertz",
    "first_order_from_stiffness",
    "without_first_order",
    "max_shift_powerlaw",
    "complete_elliptic",
]

_AGM_STEPS = 10   # quadratic convergence: enough down to k' ~ 1e-300


def first_order_powerlaw(x: ArrayLike, n: ArrayLike) -> jnp.ndarray:
    """Delta f/f0 = <max(1 + x sin t, 0)^(n-1)>/2 - 1/2 [-] (Eq. 27; Eq. 23 at n = 3/2).

    Closed form through the Gauss hypergeometric function, 1e-14 relative in the
    mean, for 1 <= n <= 4 and every x >= 0 (x > 1: contact opens, clipped).
    Gradients in x and n are finite everywhere except d/dx at x = 1 for
    1 < n <= 3/2, where the true value is -infinity (see models/ladder/hypergeometric.py).
    """
    return 0.5 * mean_power_clipped(x, jnp.asarray(n, dtype=float) - 1.0) - 0.5


def complete_elliptic(kp2: ArrayLike) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Complete elliptic integrals (K(k), E(k)) from the complementary parameter k'^2 = 1 - k^2.

    Arithmetic-geometric mean (Abramowitz & Stegun 17.6): a0 = 1, b0 = k',
    c0 = k; K = pi/(2 a_N), E = K (1 - Sum_n 2^(n-1) c_n^2). Taking k'^2 as the
    input avoids the cancellation in 1 - k^2 near k = 1. Requires 0 < k'^2 <= 1.
    """
    kp2 = jnp.asarray(kp2, dtype=float)
    a = jnp.ones_like(kp2)
    b = jnp.sqrt(kp2)
    total = 0.5 * (1.0 - kp2)
    weight = 0.5
    for _ in range(_AGM_STEPS):
        c = 0.5 * (a - b)
        a, b = 0.5 * (a + b), jnp.sqrt(a * b)
        weight = 2.0 * weight
        total = total + weight * c * c
    k_int = 0.5 * jnp.pi / a
    return k_int, k_int * (1.0 - total)


def first_order_hertz(x: ArrayLike) -> jnp.ndarray:
    """Hertz (n = 3/2) first-order shift via complete elliptic integrals [-].

    Independent of the hypergeometric route; used to cross-check it. With t = phi + pi/2,
    cos phi = 1 - 2 sin^2(theta), and k^2 = 2x/(1 + x):

        <sqrt(1 + x sin t)> = (1/pi) Int_0^pi sqrt(1 + x cos phi) dphi
                            = (2/pi) sqrt(1 + x) E(k)                        (0 <= x <= 1),

    so <sqrt(1 + sin t)> = 2 sqrt(2)/pi and the shift at x = 1 is sqrt(2)/pi - 1/2
    = -0.049842 (the paper's "about -0.05"). For x > 1 the integrand is clipped
    where 1 + x cos phi < 0; substituting k sin theta = sin psi (reciprocal
    modulus, kappa = 1/k, kappa^2 = (1 + x)/(2x)):

        <max(1 + x sin t, 0)^(1/2)> = (2/pi) sqrt(1 + x) [k E(kappa) - (k - 1/k) K(kappa)].

    d/dx diverges to -infinity at x = 1; there the gradient is ``NEG_INF_GRAD``/2.
    """
    x = jnp.abs(jnp.asarray(x, dtype=float))
    is_one = x == 1.0
    xs = jnp.where(is_one, 0.5, x)
    opened = xs > 1.0
    xo = jnp.where(opened, xs, 2.0)          # finite stand-in where a branch is unused
    # complementary parameters, both written without cancellation
    kp2 = jnp.where(opened, (xo - 1.0) / (2.0 * xo), (1.0 - xs) / (1.0 + xs))
    k_int, e_int = complete_elliptic(kp2)
    k = jnp.sqrt(2.0 * xo / (1.0 + xo))
    bracket = jnp.where(opened, k * e_int - (k - 1.0 / k) * k_int, e_int)
    mean = 2.0 / jnp.pi * jnp.sqrt(1.0 + xs) * bracket
    at_one = 2.0 * np.sqrt(2.0) / np.pi + NEG_INF_GRAD * (x - jax.lax.stop_gradient(x))
    return jnp.where(is_one, at_one, mean) / 2.0 - 0.5


def first_order_from_stiffness(
    stiffness_fn: Callable[[jnp.ndarray], jnp.ndarray],
    delta0: ArrayLike,
    x: ArrayLike,
    *,
    k0: ArrayLike | None = None,
    nodes: int = 81,
) -> jnp.ndarray:
    """Delta f/f0 = <K(delta0 (1 + x sin t))>/(2 K0) - 1/2 by quadrature [-] (Eq. 22).

    For contact laws without a closed form (JKR, DMT). ``stiffness_fn(delta)``
    gives the tangent stiffness [N/m] at overlap ``delta`` [m]; it is called
    once per quadrature node through ``jax.vmap`` over a leading node axis, so a
    closure over parameters shaped like ``delta0``/``x`` broadcasts as usual.
    K is taken as 0 where delta <= 0 (contact open; the function is never
    evaluated there). ``k0`` defaults to ``stiffness_fn(delta0)``.

    With t = pi/2 + phi the mean is (1/pi) Int_0^phi0 K(delta0 (1 + x cos phi)) dphi,
    phi0 = pi for x <= 1 and arccos(-1/x) for x > 1 (the contact arc), computed
    by tanh-sinh quadrature on [0, phi0]: exponentially convergent for a
    smooth K, and also with the algebraic endpoint singularity K ~ delta^p at the
    contact edge (x >= 1). With the default 81 nodes the power-law check in
    tests/test_shift.py is within 1e-12 (x <= 0.99, x >= 1) and 1e-9 just below
    x = 1, where the integrand is nearly singular at the endpoint.
    """
    delta0 = jnp.asarray(delta0, dtype=float)
    x = jnp.abs(jnp.asarray(x, dtype=float))
    delta0, x = jnp.broadcast_arrays(delta0, x)
    if k0 is None:
        k0 = stiffness_fn(delta0)
    u, w = tanh_sinh(nodes, h=6.4 / (nodes - 1))
    xs = jnp.where(x > 1.0, x, 2.0)
    phi0 = jnp.where(x > 1.0, jnp.arccos(-1.0 / xs), jnp.pi)
    phi = phi0[None] * jnp.asarray(u).reshape((-1,) + (1,) * x.ndim)
    delta = delta0[None] * (1.0 + x[None] * jnp.cos(phi))
    touching = delta > 0.0
    k_nodes = jax.vmap(stiffness_fn)(jnp.where(touching, delta, delta0[None]))
    k_nodes = jnp.where(touching, k_nodes, 0.0)
    weights = jnp.asarray(w).reshape((-1,) + (1,) * x.ndim)
    mean = phi0 / jnp.pi * jnp.sum(weights * k_nodes, axis=0)
    return mean / (2.0 * k0) - 0.5


def first_order_adhesive(
    module: Any, x: ArrayLike, *, load: ArrayLike, e_star: ArrayLike, radius: ArrayLike,
    gamma: ArrayLike, reference_overlap: ArrayLike | None = None,
) -> jnp.ndarray:
    """First-order Delta f/f0 of an adhesive law (``models.laws.jkr`` or ``models.laws.dmt``) [-].

    x = delta_a/delta_ref, delta_ref the law's own static overlap unless
    ``reference_overlap`` is given (the paper's Fig. 4 normalises by the Hertz delta0);
    quadrature by :func:`first_order_from_stiffness`.
    """
    kw = {"e_star": e_star, "radius": radius, "gamma": gamma}
    delta0 = module.static_overlap(load, **kw)
    k0 = module.linear_stiffness(load, **kw)
    x = jnp.asarray(x)
    x_own = x if reference_overlap is None else x * reference_overlap / delta0
    return first_order_from_stiffness(lambda d: module.stiffness(d, **kw), delta0, x_own, k0=k0)


def without_first_order(mean_ratio: ArrayLike) -> jnp.ndarray:
    """Delta f/f0 = sqrt(<K>/K0) - 1 [-]: the paper's Fig. 4 grey curves.

    ``mean_ratio`` = <K>/K0 [-] (e.g. 2 (first_order + 1/2)), positive.
    """
    return jnp.sqrt(jnp.asarray(mean_ratio, dtype=float)) - 1.0


def max_shift_powerlaw(n: ArrayLike) -> jnp.ndarray:
    """First-order shift at x = 1 versus n (paper Fig. 5) [-].

    = 2^(n-2) Gamma(n - 1/2)/(sqrt(pi) Gamma(n)) - 1/2: zero at n = 1 and n = 2,
    negative in between, positive for n > 2 (log-convexity of Gamma). Its
    minimum solves psi(n) - psi(n - 1/2) = ln 2: n* = 1.4004 with -0.05169,
    a little below the Hertz value -0.04984 at n = 3/2; the paper's "minimum
    around -0.05 close to n = 3/2" (tests/test_shift.py).
    """
    return 0.5 * mean_power_at_one(jnp.asarray(n, dtype=float) - 1.0) - 0.5
