"""Viscoelastic Hertz contact: Brilliantov et al. / Kuwabara-Kono (paper Sec. 4.2, Eqs. 8-9).

Force (Kelvin-Voigt solids, quasi-static viscous stress proportional to strain rate)::

    F = (4/3) E* R^(1/2) [ delta^(3/2) + (3/2) A delta^(1/2) d(delta)/dt ]        (paper Eq. 8)
      = k_n delta^(3/2) + gamma_n delta^(1/2) d(delta)/dt                         (paper Eq. 28)
    k_n = (4/3) E* R^(1/2),   gamma_n = (3/2) A k_n,
    A = (1/E) (1+nu)/(1-nu) [ (4/3) eta1 (1 - nu + nu^2) + eta2 (1 - 2 nu)^2 ]    (paper Eq. 9)

with the bulk viscosities eta1, eta2 in [Pa s] (the paper's "MPa.s^-1" means MPa s) and
A in [s]. References: N. V. Brilliantov, F. Spahn, J.-M. Hertzsch, T. Poeschel,
Phys. Rev. E 53, 5382 (1996); G. Kuwabara, K. Kono, Jpn. J. Appl. Phys. 26, 1230 (1987);
the form of A as printed in the paper (its refs. [26, 28]).

Sign convention: delta > 0 is compression, d(delta)/dt > 0 loading, F > 0 repulsive. On
unloading (d(delta)/dt < 0) the dissipative term is negative and, near the end of an
impact or at large velocity, can make F < 0: a tensile force that a non-adhesive
unilateral contact cannot carry. :func:`force` returns the raw Eq. 8 by default and
max(F, 0) with ``clip=True`` (the usual unilateral-contact remedy); both are 0 for
delta <= 0 (contact lost).

Linearised about the static overlap delta0 (K0 = 2 E* (R delta0)^(1/2)):
    m x'' + A K0 x' + K0 x = 0   =>   Q = m omega0 / (A K0) = 1/(omega0 A)  (paper Eqs. 29-30).

Frequency shift. The dissipative force changes damping, not stiffness, to first order,
so the correct first-order shift is the Hertz one (:func:`shift_first_order`). The paper's
Eq. 25 adds an extra term; :func:`paper_eq25_extra` is what that term evaluates to when
the derivative in it is taken by finite-difference secants on a uniform grid, and
:func:`shift_paper_eq25` reproduces the paper's Fig. 4 black dashed curve. See
:func:`paper_eq25_extra` for the derivation of why the term is zero and where the
artefact comes from.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax.typing import ArrayLike

from beadrod.models.ladder.first_order import first_order_hertz, without_first_order
from beadrod.models.laws import hertz
from beadrod.models.safe_math import safe_pow, safe_sqrt

__all__ = [
    "viscosity_factor",
    "damping_constant",
    "kuwabara_kono_gamma",
    "force",
    "linear_q",
    "linear_inverse_q",
    "eta_from_damping_constant",
    "eta_from_q",
    "shift_first_order",
    "paper_eq25_extra",
    "shift_paper_eq25",
    "shift_paper_without_first_order",
]


def viscosity_factor(poisson: ArrayLike) -> jnp.ndarray:
    """c(nu) = (1+nu)/(1-nu) [(4/3)(1 - nu + nu^2) + (1 - 2 nu)^2] [-], so A = c eta / E for
    eta1 = eta2 = eta (paper Eq. 9)."""
    nu = jnp.asarray(poisson)
    return (1 + nu) / (1 - nu) * (4.0 / 3.0 * (1 - nu + nu**2) + (1 - 2 * nu) ** 2)


def damping_constant(
    *, eta1: ArrayLike, eta2: ArrayLike | None = None, young: ArrayLike, poisson: ArrayLike
) -> jnp.ndarray:
    """A [s] of paper Eq. 9 from the bulk viscosities eta1, eta2 [Pa s]; ``eta2=None`` means
    eta2 = eta1 (the paper's eta1 = eta2 = eta). Linear in eta: finite gradients at eta = 0."""
    eta2 = eta1 if eta2 is None else eta2
    nu = jnp.asarray(poisson)
    return (
        (1 + nu) / (1 - nu) * (4.0 / 3.0 * eta1 * (1 - nu + nu**2) + eta2 * (1 - 2 * nu) ** 2)
        / young
    )


def kuwabara_kono_gamma(
    *, e_star: ArrayLike, radius: ArrayLike, damping_constant: ArrayLike
) -> jnp.ndarray:
    """gamma_n = (3/2) A k_n [kg m^-1/2 s^-1] with k_n = (4/3) E* R^(1/2) (paper Eqs. 8, 28)."""
    kn = hertz.stiffness_constant(e_star=e_star, radius=radius)
    return 1.5 * damping_constant * kn


def force(
    delta: ArrayLike,
    delta_dot: ArrayLike,
    *,
    e_star: ArrayLike,
    radius: ArrayLike,
    damping_constant: ArrayLike,
    clip: bool = False,
) -> jnp.ndarray:
    """F = k_n (delta^(3/2) + (3/2) A delta^(1/2) delta_dot) [N] (paper Eq. 8).

    ``delta`` [m] (> 0 compression), ``delta_dot`` [m/s]. 0 for delta <= 0. With
    ``clip=True`` returns max(F, 0): no tension on fast unloading (see module docstring).
    """
    kn = hertz.stiffness_constant(e_star=e_star, radius=radius)
    f = kn * (safe_pow(delta, 1.5) + 1.5 * damping_constant * safe_pow(delta, 0.5) * delta_dot)
    return jnp.maximum(f, 0.0) if clip else f


def linear_q(*, damping_constant: ArrayLike, omega0: ArrayLike) -> jnp.ndarray:
    """Q = 1/(omega0 A) [-] of the linearised oscillator (paper Eq. 30, since K0 = m omega0^2).

    Diverges (returns inf) at A = 0; use :func:`linear_inverse_q` where A may vanish.
    """
    return 1.0 / (omega0 * damping_constant)


def linear_inverse_q(*, damping_constant: ArrayLike, omega0: ArrayLike) -> jnp.ndarray:
    """1/Q = omega0 A [-]: finite, with finite gradients, down to A = 0."""
    return omega0 * damping_constant


def eta_from_damping_constant(
    damping_constant: ArrayLike, *, young: ArrayLike, poisson: ArrayLike
) -> jnp.ndarray:
    """eta [Pa s] (eta1 = eta2 = eta) giving damping constant A [s]: eta = A E / c(nu)."""
    return damping_constant * young / viscosity_factor(poisson)


def eta_from_q(
    q: ArrayLike, *, omega0: ArrayLike, young: ArrayLike, poisson: ArrayLike
) -> jnp.ndarray:
    """eta [Pa s] (eta1 = eta2) whose linear Q at angular frequency omega0 [rad/s] is ``q``."""
    return eta_from_damping_constant(1.0 / (q * omega0), young=young, poisson=poisson)


def shift_first_order(x: ArrayLike) -> jnp.ndarray:
    """Correct first-order Delta f/f0 of the viscoelastic law at x = delta_a/delta0 [-].

    Identical to the Hertz first-order shift: damping does not enter at this order (the
    dissipative force has no component in phase with the displacement; see
    :func:`paper_eq25_extra`). Damping moves the response peak only at order 1/Q^2,
    which the forced-response rungs (harmonic balance, time integration) capture.
    """
    return first_order_hertz(x)


def paper_eq25_extra(
    x: ArrayLike, *, damping_constant: ArrayLike, omega: ArrayLike
) -> jnp.ndarray:
    """The extra term of the paper's Eq. 25 as the paper evaluated it: a secant artefact.

        E(x) = -(A omega / 4) (sqrt(1 + x) - sqrt(1 - x))      [-]

    with A [s], omega [rad/s] (the paper uses the resonance omega ~ omega0). NOT physics.
    For x > 1 sqrt(1 - x) is clipped at 0 (by construction: beyond x = 1 the secant recipe
    has no meaning either). d/dx diverges as x -> 1- (true); the gradient returned at
    x >= 1 is the one-sided value of the clipped form, finite.

    What the term should be. Write delta = delta0 (1 + x sin t), s = x sin t,
    h(t) = (1 + x sin t)^(1/2) x cos t (the dissipative force is k_n (3/2) A omega
    delta0^(3/2) h). Eq. 25's extra term is (A omega / 4 pi) Int_0^2pi dh/ds dt, and
    every well-defined reading of dh/ds gives zero:

    1. Along the orbit: dh/ds = h'(t)/s'(t) = (1/2) x cos t (1 + x sin t)^(-1/2)
       - (1 + x sin t)^(1/2) tan t. The first part is d/dt of a periodic function
       (integral 0). The second has poles at t = pi/2, 3pi/2 (turning points, s' = 0)
       and its principal value vanishes: under t -> pi - t, sin t is unchanged and tan t
       changes sign, and that reflection maps each pole's symmetric neighbourhood onto
       itself.
    2. d/d(delta_a) at fixed t, divided by sin t (= d/d(delta_a sin t)): the same first
       part plus (1 + x sin t)^(1/2) cot t, odd under t -> pi - t, PV zero.
    3. In-phase first harmonic of the dissipative force: Int h sin t dt ∝
       Int (1 + x sin t)^(1/2) cos t sin t dt = 0 (odd under t -> pi - t). The
       dissipative force is purely out of phase with the displacement: it damps.
    4. d/d(delta) at fixed velocity: ∝ Int (1 + x sin t)^(-1/2) cos t dt = 0
       (exact derivative of a periodic function).

    Where the paper's number comes from. Evaluate dh/ds by forward secants
    diff(h)/diff(s) on t = linspace(0, 2 pi, N) (endpoint included, spacing
    Dt = 2 pi/(N-1)) and average (any Riemann sum). Near a turning point t*, s is flat to
    second order while h is linear, so the secant over the interval
    [t* + (k - alpha) Dt, t* + (k + 1 - alpha) Dt] (alpha in [0, 1) the fraction of the
    straddling interval before t*) is ~ +-c/(Dt (k + beta)), beta = 1/2 - alpha, with
    c = sqrt(1 + x) at pi/2 and sqrt(1 - x) at 3pi/2. Their Riemann sum does not vanish
    as Dt -> 0: Sum_k 1/(k + beta) = pi cot(pi beta) leaves the finite remainder
        (1/4) [sqrt(1 + x) cot(pi beta1) + sqrt(1 - x) cot(pi beta2)]   (times A omega).
    For N divisible by 4, pi/2 sits at alpha = 3/4 and 3pi/2 at alpha = 1/4 of their
    intervals: cot(-pi/4) = -1, cot(pi/4) = 1 give exactly E(x) above. (N = 2 mod 4
    flips the sign, N = 1 mod 4 puts grid points on the turning points and returns the
    correct 0, N = 3 mod 4 divides by zero.) The tests reproduce all of this numerically.
    """
    x = jnp.asarray(x)
    return -0.25 * damping_constant * omega * (safe_sqrt(1.0 + x) - safe_sqrt(1.0 - x))


def shift_paper_eq25(
    x: ArrayLike, *, damping_constant: ArrayLike, omega: ArrayLike
) -> jnp.ndarray:
    """The paper's viscoelastic Delta f/f0 (its Eq. 25, Fig. 4 black dashed curve) [-].

    = Hertz first-order shift + :func:`paper_eq25_extra`. Reproduces the paper's curve;
    it is not a physical prediction (the extra term is a finite-difference artefact).
    x > 1: the Hertz part uses the clipped (contact-loss) integrand of models.ladder.first_order and
    sqrt(1 - x) is clipped at 0.
    """
    return first_order_hertz(x) + paper_eq25_extra(
        x, damping_constant=damping_constant, omega=omega
    )


def shift_paper_without_first_order(
    x: ArrayLike, *, damping_constant: ArrayLike, omega: ArrayLike
) -> jnp.ndarray:
    """The paper's Fig. 4 grey curve: sqrt(<K>/K0) - 1 with the paper's Eq. 24 K [-].

    <K>/K0 = 1 + 2 (Delta f/f0 of :func:`shift_paper_eq25`), since the first-order shift is
    <K>/(2 K0) - 1/2. Inherits the artefact of :func:`paper_eq25_extra`.
    """
    ratio = 1.0 + 2.0 * shift_paper_eq25(x, damping_constant=damping_constant, omega=omega)
    return without_first_order(ratio)


def _law(split: bool):
    from beadrod.models.law import (
        YOUNG,
        ContactLaw,
        Param,
        Physics,
        Presentation,
        Prior,
        SamplerHints,
    )
    from beadrod.models.rungs import LADDER
    from beadrod.models.tables.powerlaw_backbone import backbone_shift_clipped
    from beadrod.models.tables.surrogate import within_amplitude

    def eta(name, what):
        return Param(name, "Pa s", {"eta": r"$\eta$", "eta_shift": r"$\eta_\mathrm{shift}$",
                                    "eta_q": r"$\eta_Q$"}[name], Prior("loguniform", 1e2, 1e8),
                     f"Bulk viscosity eta1 = eta2 {what} (paper Eq. 9). Prior LogUniform(1e2, "
                     "1e8) Pa s: unknown over decades; the paper's shift fit gives 1.05e6, its "
                     "measured Q = 20-100 implies 5e4-3e5; the interval brackets both by more "
                     "than two decades either way (scale-invariant).",
                     display=("MPa s", 1e6), scene_key="viscosity", bounds="viscosity_Pa_s",
                     what="the viscosity")

    if split:
        params = (YOUNG, eta("eta_shift", "that enters the shift (only under the paper's "
                             "Eq. 25)"), eta("eta_q", "that sets the linear Q"))
        e_shift, e_q = "eta_shift", "eta_q"
    else:
        params = (YOUNG, eta("eta", "(one viscosity for shift and Q)"))
        e_shift = e_q = "eta"

    def a(kw, name):
        return damping_constant(eta1=kw[name], eta2=kw[name], young=kw["young"],
                                poisson=kw["poisson"])

    return ContactLaw(
        name="viscoelastic_split" if split else "viscoelastic",
        params=params,
        physics=Physics(
            **hertz.mechanics(),
            rungs=(*LADDER, "paper_eq25"),
            shifts={"first_order": lambda x, **_: shift_first_order(x),
                    "backbone": lambda x, **_: backbone_shift_clipped(x, hertz.EXPONENT),
                    "paper_eq25": lambda x, *, omega0, **kw: shift_paper_eq25(
                        x, damping_constant=a(kw, e_shift), omega=omega0)},
            # the table holds its x = 2 value beyond; the inference counts no point there
            domains={"backbone": lambda x, **_: within_amplitude(x)},
            linear_q=lambda *, omega0, **kw: linear_q(damping_constant=a(kw, e_q),
                                                      omega0=omega0),
            # q = A omega k_eq(U) (the first harmonic of A dF/dt) and k_eq = m omega^2 on
            # the backbone: L = A omega0 Omega^3 (docs/damping.md)
            loss_exponent=3.0,
        ),
        presentation=Presentation(
            label="viscoelastic (split η)" if split else "viscoelastic",
            color="#009E73" if not split else "#56B4E9",
            reference="Brilliantov et al. 1996; Kuwabara & Kono 1987; paper Eqs. 8-9, 25, 30",
            description=("Hertz + Kuwabara-Kono damping; " + (
                "separate viscosities for the shift (Eq. 25) and for Q: the tension test"
                if split else "one viscosity predicts both the shift (Eq. 25) and Q")),
            tension_role="split" if split else "shared",
            tension_param="eta",
        ),
        # relative fit time (models.law.SamplerHints.cost): the cheapest on the embedded data
        sampler=SamplerHints(cost=0.8),
    )


LAW = _law(split=False)
"""The viscoelastic law, one viscosity (:class:`models.law.ContactLaw`)."""
SPLIT_LAW = _law(split=True)
"""The viscoelastic law with separate viscosities for shift and Q (the tension test)."""
__all__ += ["LAW", "SPLIT_LAW"]
