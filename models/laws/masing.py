"""Masing hysteresis (microslip) element: power-law virgin curve, loops, describing function.

Virgin loading curve of the contact's dynamic displacement u [m] (u = 0 at the static
overlap), for 1 < m <= 3 and a >= 0 [N/m^m]::

    f(u) = k u - a |u|^(m-1) u                                              [N]

m = 2 is Rayleigh's law of hysteresis (and the small-amplitude limit of Mindlin-Deresiewicz
microslip, whose loss per cycle grows as the cube of the amplitude); a Segalman-type Iwan
density phi^chi has m = 2 + chi. Masing's rule builds every branch from the virgin curve:
from a reversal (u_r, f_r), f(u) = f_r + 2 f((u - u_r)/2); from (U, f(U)) this is the
descending branch f_d(u) = f(U) - 2 f((U - u)/2), and the ascending one is f_a(u) = -f_d(-u).
On u = U cos(theta) (U >= 0) the steady loop gives, with the branches' linear part k left
out of every "change"::

    D   = loop area = 4 a U^(m+1) (m-1)/(m+1)                               [J]
    dk  = (1/(pi U)) Int_0^2pi f cos(theta) d theta - k
        = 4 a U^(m-1) I_m / (pi 2^m) = -c(m) a U^(m-1)                       [N/m]
    q   = -(1/(pi U)) Int_0^2pi f sin(theta) d theta = D/(pi U^2)
        = 4 a U^(m-1) (m-1)/(pi (m+1))                                      [N/m]
    I_m = Int_0^pi (1 - cos t)^m cos t dt = -2^m J(m) m/(m+1)   (I_2 = -pi)  [-]
    J(m) = sqrt(pi) Gamma(m+1/2)/Gamma(m+1),  c(m) = 4 m J(m)/(pi (m+1))    [-]

(write 1 - cos t = 2 sin^2(t/2), cos t = 1 - 2 sin^2(t/2), and use the Wallis integral
Int_0^pi sin^(2m)(t/2) dt = J(m) with J(m+1) = J(m)(m+1/2)/(m+1)). dk is the first-harmonic
in-phase (describing-function) stiffness change, q the quadrature stiffness: the element
acts on the first harmonic as a spring k + dk in parallel with a dashpot c_eq = q/omega.

Dimensionless form, as the project writes its shifts: x = U/delta0 >= 0 (dynamic amplitude
over static overlap), k0 [N/m] the contact's linear stiffness (= m_bead omega0^2). The
strength h >= 0 is the hysteretic first-order frequency drop at x = 1,
h = -dk(U = delta0)/(2 k0), so a = 2 h k0/(c(m) delta0^(m-1)) and::

    dk/k0         = -2 h x^(m-1)                     (stiffness_change)
    df/f0         = dk/(2 k0) = -h x^(m-1)           (shift_first_order)
    d(1/Q) = q/k0 = h rho(m) x^(m-1)                 (loss_change)
    rho(m) = d(1/Q)/|df/f0| = 2 q/|dk| = 2 (m-1)/(m J(m))
           = 2 (m-1) Gamma(m+1)/(sqrt(pi) m Gamma(m+1/2))   (rho(2) = 8/(3 pi))

References: G. Masing, Proc. 2nd Int. Congr. Appl. Mech., Zuerich (1926) 332-335 (the
branch rule); Lord Rayleigh, Phil. Mag. 23, 225 (1887) (m = 2); W. D. Iwan, J. Appl. Mech. 33,
893 (1966) and 34, 612 (1967) (the parallel Jenkins model, its Masing behaviour and its
describing function); D. J. Segalman, J. Appl. Mech. 72, 752 (2005) (power-law slip
densities, loss ~ U^(3+chi)); K. L. Johnson, *Contact Mechanics* (CUP 1985), Sec. 7.4;
A. Gelb, W. E. Vander Velde, *Multiple-Input Describing Functions* (McGraw-Hill 1968).

Numerics: every x^(m-1) goes through safe_pow (value 0 and a finite gradient at x = 0, where
the true slope in x is infinite for m < 2); Gamma ratios go through gammaln; strength 0
gives exactly 0. The formulas hold for 1 < m <= 3 and stay finite, with finite gradients,
from m = 1 (rho -> 0 linearly) to m = 3. The power law is a softening curve: its tangent
k - a m |u|^(m-1) vanishes at |u| = (k/(a m))^(1/(m-1)), and loops are physical only for
amplitudes below it.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax.scipy.special import gammaln
from jax.typing import ArrayLike

from beadrod.models.safe_math import safe_pow

__all__ = [
    "wallis_ratio",
    "harmonic_integral",
    "in_phase_coefficient",
    "loss_to_shift_ratio",
    "virgin_force",
    "branch_force",
    "loop_force",
    "loop_area",
    "in_phase_change",
    "quadrature_stiffness",
    "coefficient_from_strength",
    "strength_from_coefficient",
    "stiffness_change",
    "loss_change",
    "shift_first_order",
    "iwan_element",
    "iwan_force",
]

_SQRT_PI = 1.7724538509055159


def wallis_ratio(exponent: ArrayLike) -> jnp.ndarray:
    """J(m) = Int_0^pi sin^(2m)(t/2) dt = sqrt(pi) Gamma(m+1/2)/Gamma(m+1) [-] (J(2) = 3 pi/8).

    Through gammaln: finite, with a finite gradient, for every m >= 0.
    """
    m = jnp.asarray(exponent)
    return _SQRT_PI * jnp.exp(gammaln(m + 0.5) - gammaln(m + 1.0))


def harmonic_integral(exponent: ArrayLike) -> jnp.ndarray:
    """I_m = Int_0^pi (1 - cos t)^m cos t dt = -2^m J(m) m/(m+1) [-]; I_2 = -pi.

    The same as -2^(m+1) W(m) m/(m+1) with W = J/2 = (sqrt(pi)/2) Gamma(m+1/2)/Gamma(m+1).
    """
    m = jnp.asarray(exponent)
    return -jnp.exp2(m) * wallis_ratio(m) * m / (m + 1.0)


def in_phase_coefficient(exponent: ArrayLike) -> jnp.ndarray:
    """c(m) = 4 m Gamma(m+1/2)/(sqrt(pi) (m+1) Gamma(m+1)) [-], so dk = -c(m) a U^(m-1).

    c(1) = 1, c(2) = 1, c(3) = 15/16: nearly constant, which is why the strength h
    (a frequency drop) and the exponent m are nearly uncorrelated.
    """
    m = jnp.asarray(exponent)
    return 4.0 * m * wallis_ratio(m) / (jnp.pi * (m + 1.0))


def loss_to_shift_ratio(exponent: ArrayLike) -> jnp.ndarray:
    """rho(m) = d(1/Q)/|df/f0| = 2 (m-1) Gamma(m+1)/(sqrt(pi) m Gamma(m+1/2)) [-].

    The small-shift ratio of the added loss to the frequency drop (both ~ x^(m-1), so it
    does not depend on the amplitude); rho(2) = 8/(3 pi), rho -> 4 (m-1)/pi as m -> 1.
    """
    m = jnp.asarray(exponent)
    return 2.0 * (m - 1.0) / (m * wallis_ratio(m))


def virgin_force(u: ArrayLike, *, a: ArrayLike, m: ArrayLike, k: ArrayLike = 0.0
                 ) -> jnp.ndarray:
    """f(u) = k u - a |u|^(m-1) u [N] for u [m], a [N/m^m], k [N/m] (default: the
    hysteretic part alone; a linear part passes Masing's rule unchanged). Odd in u."""
    u = jnp.asarray(u)
    return k * u - a * jnp.sign(u) * safe_pow(jnp.abs(u), m)


def branch_force(u: ArrayLike, *, u_rev: ArrayLike, f_rev: ArrayLike, a: ArrayLike,
                 m: ArrayLike, k: ArrayLike = 0.0) -> jnp.ndarray:
    """Masing branch from the reversal (u_rev [m], f_rev [N]): f_rev + 2 f((u - u_rev)/2) [N].

    With u_rev = U, f_rev = f(U): the descending branch f(U) - 2 f((U - u)/2); with
    u_rev = -U, f_rev = f(-U): the ascending one, -f_d(-u). Valid while u moves away from
    u_rev and |u - u_rev| stays below twice the largest earlier excursion (else the branch
    rejoins the virgin curve or an older branch, which Masing's extended rules handle).
    """
    return f_rev + 2.0 * virgin_force((jnp.asarray(u) - u_rev) / 2.0, a=a, m=m, k=k)


def loop_force(theta: ArrayLike, *, amplitude: ArrayLike, a: ArrayLike, m: ArrayLike,
               k: ArrayLike = 0.0) -> jnp.ndarray:
    """Force [N] on the steady loop at u = U cos(theta), U = ``amplitude`` [m] >= 0.

    theta mod 2 pi in [0, pi]: descending branch from (U, f(U)); else ascending from
    (-U, f(-U)).
    """
    theta = jnp.mod(jnp.asarray(theta), 2.0 * jnp.pi)
    u = amplitude * jnp.cos(theta)
    top = virgin_force(amplitude, a=a, m=m, k=k)
    down = branch_force(u, u_rev=amplitude, f_rev=top, a=a, m=m, k=k)
    up = branch_force(u, u_rev=-amplitude, f_rev=-top, a=a, m=m, k=k)
    return jnp.where(theta <= jnp.pi, down, up)


def loop_area(amplitude: ArrayLike, *, a: ArrayLike, m: ArrayLike) -> jnp.ndarray:
    """D = 4 a U^(m+1) (m-1)/(m+1) [J], the energy dissipated per cycle at amplitude U [m]."""
    m = jnp.asarray(m)
    return 4.0 * a * safe_pow(amplitude, m + 1.0) * (m - 1.0) / (m + 1.0)


def in_phase_change(amplitude: ArrayLike, *, a: ArrayLike, m: ArrayLike) -> jnp.ndarray:
    """dk = 4 a U^(m-1) I_m/(pi 2^m) = -c(m) a U^(m-1) [N/m], the describing-function
    stiffness change at amplitude U [m] (dk = -a U at m = 2); 0 at U = 0."""
    return -in_phase_coefficient(m) * a * safe_pow(amplitude, jnp.asarray(m) - 1.0)


def quadrature_stiffness(amplitude: ArrayLike, *, a: ArrayLike, m: ArrayLike) -> jnp.ndarray:
    """q = D/(pi U^2) = 4 a U^(m-1) (m-1)/(pi (m+1)) [N/m], the loss (quadrature) stiffness
    at amplitude U [m]; an equivalent dashpot q/omega. 0 at U = 0."""
    m = jnp.asarray(m)
    return 4.0 * a * safe_pow(amplitude, m - 1.0) * (m - 1.0) / (jnp.pi * (m + 1.0))


def coefficient_from_strength(strength: ArrayLike, exponent: ArrayLike, *, k0: ArrayLike,
                              delta0: ArrayLike) -> jnp.ndarray:
    """a = 2 h k0/(c(m) delta0^(m-1)) [N/m^m] for the strength h [-], k0 [N/m], delta0 [m]
    (> 0): the coefficient whose first-order frequency drop at U = delta0 is h."""
    m = jnp.asarray(exponent)
    return 2.0 * strength * k0 / (in_phase_coefficient(m) * jnp.power(delta0, m - 1.0))


def strength_from_coefficient(a: ArrayLike, exponent: ArrayLike, *, k0: ArrayLike,
                              delta0: ArrayLike) -> jnp.ndarray:
    """h = c(m) a delta0^(m-1)/(2 k0) [-], the inverse of :func:`coefficient_from_strength`."""
    m = jnp.asarray(exponent)
    return in_phase_coefficient(m) * a * jnp.power(delta0, m - 1.0) / (2.0 * k0)


def stiffness_change(x: ArrayLike, *, strength: ArrayLike, exponent: ArrayLike
                     ) -> jnp.ndarray:
    """dk/k0 = -2 h x^(m-1) [-] at x = U/delta0 >= 0; exactly 0 at h = 0 or x = 0."""
    return -2.0 * strength * safe_pow(x, jnp.asarray(exponent) - 1.0)


def shift_first_order(x: ArrayLike, *, strength: ArrayLike, exponent: ArrayLike
                      ) -> jnp.ndarray:
    """df/f0 = dk/(2 k0) = -h x^(m-1) [-], the element's first-order frequency shift."""
    return -strength * safe_pow(x, jnp.asarray(exponent) - 1.0)


def loss_change(x: ArrayLike, *, strength: ArrayLike, exponent: ArrayLike) -> jnp.ndarray:
    """d(1/Q) = q/k0 = h rho(m) x^(m-1) [-], the element's added inverse quality factor.

    = rho(m) |df/f0| with rho from :func:`loss_to_shift_ratio` (q/k0 = (1/2) rho |dk|/k0).
    """
    m = jnp.asarray(exponent)
    return strength * loss_to_shift_ratio(m) * safe_pow(x, m - 1.0)


def iwan_element(n: int, *, a: ArrayLike, m: ArrayLike, phi_max: ArrayLike | None = None,
                 k_total: ArrayLike | None = None) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(stiffnesses k_i [N/m], slip displacements phi_i [m]) of n Jenkins elements in
    parallel (an Iwan element) whose virgin curve is k_I u - a u^m on 0 <= u <= phi_max.

    The continuous element has the slip-displacement density
    rho(phi) = a m (m-1) phi^(m-2) on (0, phi_max] (force k_I u - a u^m, since
    F''(u) = -rho(u)), total stiffness k_I = a m phi_max^(m-1), where the virgin tangent
    reaches 0; beyond phi_max every slider slips and the force stays at
    a (m-1) phi_max^m. Give ``phi_max`` [m] or ``k_total`` = k_I [N/m] (then
    phi_max = (k_I/(a m))^(1/(m-1))). A contact of linear stiffness k is
    f(u) = (k - k_I) u + F_I(u): loops of amplitude U <= phi_max then obey every formula of
    this module.

    Discretisation: equal stiffness k_I/n per slider, bins [phi_(j-1), phi_j] with
    phi_j = phi_max (j/n)^(1/(m-1)) (equal shares of the cumulative stiffness a m phi^(m-1)),
    each slider slipping at its bin's centroid
    phi_j* = Int phi rho / Int rho = ((m-1)/m) phi_max n [s_j^p - s_(j-1)^p], s = j/n,
    p = m/(m-1). Why: the density is singular at phi = 0 for m < 2 (a midpoint grid in phi
    would put almost no sliders where most of the stiffness is), equal shares put
    sliders where the stiffness is, and the centroid keeps both the stiffness and the
    first moment of every bin: the virgin force is exact at every bin edge.
    """
    if (phi_max is None) == (k_total is None):
        raise ValueError("give exactly one of phi_max and k_total")
    m = jnp.asarray(m)
    if phi_max is None:
        phi_max = jnp.power(k_total / (a * m), 1.0 / (m - 1.0))
    k_i = a * m * jnp.power(phi_max, m - 1.0)
    # s = j/n from j = 1: s^p at s = 0 would have a NaN gradient in p (log 0)
    s_p = jnp.power(jnp.arange(1, n + 1) / n, m / (m - 1.0))
    s_p = jnp.concatenate([jnp.zeros(1, dtype=s_p.dtype), s_p])
    slip = (m - 1.0) / m * phi_max * n * jnp.diff(s_p)
    return jnp.full(n, k_i / n), slip


def iwan_force(u: ArrayLike, z: ArrayLike, stiff: ArrayLike, slip: ArrayLike
               ) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(force [N], new slider positions [m]) of an Iwan element moved to displacement u [m].

    Slider i (spring stiff_i [N/m] in series with a Coulomb slider of slip force
    stiff_i slip_i) carries the spring elongation e_i = u - z_i, |e_i| <= slip_i; ``z``
    (shape (..., n)) holds the slider positions, zeros for a virgin element. Elastic
    predictor e = u - z, return map e -> clip(e, -slip, slip), z' = u - e;
    F = Sum_i stiff_i e_i. Rate independent and exact whenever u moves monotonically from
    the previous call's displacement, so a time stepper (jax.lax.scan) calls it once per
    step with the committed state.
    """
    u = jnp.asarray(u)[..., None]
    e = jnp.clip(u - z, -slip, slip)
    return jnp.sum(stiff * e, axis=-1), u - e
