"""The nondimensional base-excited contact oscillator (bead on a vibrating rod end).

Physical model [SI]: the rod end under the bead moves u(t) = U sin(omega t); the
bead (mass m, vertical position z measured from rest) has overlap
delta = delta0 + u - z and obeys

    m z'' = F(delta, delta') - F0,      F = 0 for delta <= 0 (contact loss),

with F0 = m g (+ any extra load) and F(delta0, 0) = F0 defining delta0.

Nondimensional form: y = delta/delta0, tau = omega0 t with omega0^2 = K0/m,
g(y, y') = F/F0 (so g(1, 0) = 1) and slope s = K0 delta0/F0 (= n for F ~ delta^n).
The relative coordinate q = y - 1 = (delta - delta0)/delta0 obeys

    q'' + (g(1 + q, q') - 1)/s = -E Omega^2 sin(Omega tau),                 (*)

with drive level E = U/delta0 and frequency ratio Omega = omega/omega0. The bead's
own displacement is w = z/delta0 = E sin(Omega tau) - q.

Reported amplitude everywhere in the dynamics modules: x = first-harmonic amplitude
of q at the drive frequency, i.e. delta_a/delta0 with delta = delta0 + delta_a sin(.)
(the amplitude convention of models.ladder.backbone). Near resonance the bead's absolute first
harmonic differs from it by the base motion E (= x/Q at the peak); both are returned
where a sweep is measured.

Contact laws are small equinox pytrees with a ``force(y, yd)`` method returning the
normalised force g and a ``slope`` attribute s; every parameter is a differentiable
leaf. Dissipative terms act only in contact and the total force is clipped at F >= 0
(the Kuwabara-Kono force turns tensile late in unloading; a non-adhesive contact
cannot pull, so it is set to zero there, the usual convention in granular dynamics).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
from jax.typing import ArrayLike

from beadrod.models.safe_math import safe_pow

__all__ = [
    "ContactLaw",
    "PowerLaw",
    "Viscoelastic",
    "CustomLaw",
    "hertz_oscillator",
    "rhs",
    "drive_level",
    "frequency_ratio",
]


class ContactLaw(eqx.Module):
    """Interface: normalised force g(y, y') [-] and slope s = K0 delta0/F0 [-]."""

    def force(self, y: ArrayLike, yd: ArrayLike) -> jnp.ndarray:  # pragma: no cover
        raise NotImplementedError

    @property
    def slope(self) -> jnp.ndarray:  # pragma: no cover
        raise NotImplementedError

    @property
    def conservative(self) -> bool:
        return False


def _in_contact(y, total):
    """Unilateral clip: F = max(total, 0) in contact, 0 out of contact."""
    return jnp.where(y > 0, jnp.maximum(total, 0.0), 0.0)


class PowerLaw(ContactLaw):
    """g = y^n + 2 zeta n y^(n-1) y' (in contact), clipped at g >= 0; n = 3/2 is Hertz.

    ``zeta`` is an optional stiffness-proportional damping ratio: a contact dashpot
    c = 2 zeta K_N(delta)/omega0. Linearised, (*) becomes q'' + 2 zeta q' + q = ...,
    so the low-drive quality factor is 1/(2 zeta); unlike a constant dashpot it
    vanishes continuously as the contact opens (a constant dashpot makes the force
    jump at every impact, which is unphysical and ruins fixed-step integrators).
    For n = 3/2 it has the Kuwabara-Kono form with A omega0 = 2 zeta.
    """

    n: Any = 1.5
    zeta: Any = 0.0

    def force(self, y, yd):
        n = jnp.asarray(self.n)
        return _in_contact(y, safe_pow(y, n) + 2.0 * self.zeta * n * safe_pow(y, n - 1.0) * yd)

    @property
    def slope(self):
        return jnp.asarray(self.n)

    def potential(self, y):
        """G(y) = int_0^y g dy' for the elastic part, y^(n+1)/(n+1) (0 for y <= 0)."""
        n = jnp.asarray(self.n)
        return safe_pow(y, n + 1.0) / (n + 1.0)

    @property
    def conservative(self) -> bool:
        return True


def hertz_oscillator(zeta: ArrayLike = 0.0) -> PowerLaw:
    """Hertz contact, n = 3/2."""
    return PowerLaw(n=1.5, zeta=zeta)


class Viscoelastic(ContactLaw):
    """Kuwabara-Kono / Brilliantov: F = k (delta^(3/2) + (3/2) A delta^(1/2) delta').

    Normalised: g = y^(3/2) + (3/2) (A omega0 + 2 zeta) y^(1/2) y', clipped at g >= 0,
    s = 3/2. ``a_omega0`` = A omega0 [-]; linearised Q = 1/(A omega0 + 2 zeta).
    """

    a_omega0: Any = 0.0
    zeta: Any = 0.0

    def force(self, y, yd):
        diss = 1.5 * (self.a_omega0 + 2.0 * self.zeta) * safe_pow(y, 0.5) * yd
        return _in_contact(y, safe_pow(y, 1.5) + diss)

    @property
    def slope(self):
        return jnp.asarray(1.5)


class CustomLaw(ContactLaw):
    """Any normalised law: ``fn(y, yd, params)`` -> g with g(1, 0) = 1, slope s given.

    For adhesive laws (JKR/DMT) pass their normalised force F(delta0 y)/F0 and
    K0 delta0/F0; ``fn`` must do its own loss-of-contact logic (an adhesive contact
    may pull, F < 0). The optional ``zeta`` adds the stiffness-proportional dashpot
    2 zeta (d fn/dy)(y, 0) y' where y > 0 (see :class:`PowerLaw`).
    """

    fn: Callable = eqx.field(static=True)
    params: Any
    slope_value: Any
    zeta: Any = 0.0

    def force(self, y, yd):
        y = jnp.asarray(y, dtype=float)
        _, k = jax.jvp(lambda v: self.fn(v, 0.0, self.params), (y,), (jnp.ones_like(y),))
        return self.fn(y, yd, self.params) + jnp.where(y > 0, 2.0 * self.zeta * k * yd, 0.0)

    @property
    def slope(self):
        return jnp.asarray(self.slope_value)


def rhs(q: ArrayLike, v: ArrayLike, tau: ArrayLike, *, law: ContactLaw,
        omega: ArrayLike, drive: ArrayLike) -> jnp.ndarray:
    """q'' from (*): -(g(1+q, q') - 1)/s - E Omega^2 sin(Omega tau) [-]."""
    g = law.force(1.0 + q, v)
    return -(g - 1.0) / law.slope - drive * omega**2 * jnp.sin(omega * tau)


def drive_level(base_amplitude: ArrayLike, delta0: ArrayLike) -> jnp.ndarray:
    """E = U/delta0 [-]: base (rod-end) displacement amplitude over static overlap."""
    return jnp.asarray(base_amplitude) / delta0


def frequency_ratio(frequency: ArrayLike, f0: ArrayLike) -> jnp.ndarray:
    """Omega = f/f0 [-]."""
    return jnp.asarray(frequency) / f0
