"""The dynamic rungs for any contact law, from its force alone: series, harmonic balance,
time integration.

Given a :class:`models.law.ContactLaw` (force F(delta; theta) [N]) at the overlap delta0
[m] the amplitude x = delta_a/delta0 refers to, the forced oscillator of
:mod:`models.ladder.oscillator` is built from the force by autodiff:

    g(y, y') = [F(delta0 y) + 2 zeta K(delta0 y) delta0 y'] / F0,   y = delta/delta0,
    s = K0 delta0 / F0,   F0 = F(delta0),  K = dF/d delta,  K0 = K(delta0),

with g = 0 where delta <= 0 (the surfaces part: the convention of
:func:`models.ladder.generic.backbone_shift`) and, where the elastic force is compressive, the
total clipped at g >= 0 (a non-adhesive contact cannot pull; the convention of
:class:`models.ladder.oscillator.PowerLaw`, which this reproduces for F ~ delta^n). F0 = F(delta0)
equals the load at the static overlap; for an overlap implied by a measured f0 the
stiffness scale s_p of F_p = s_p F cancels from g and s. The damping is
stiffness-proportional, zeta = 1/(2 Q): linearised, q'' + 2 zeta q' + q = drive, so Q is
the low-drive quality factor. Q is the law's own linear Q (``linear_q``) where it has a
loss channel, else the keyword ``q_factor`` (default 50, as in
:mod:`models.ladder.powerlaw_ladder`). For
the Kuwabara-Kono viscoelastic law the stiffness-proportional dashpot is its own:
A K(delta) delta' with A omega0 = 1/Q.

Rungs (Delta f/f0 [-] at first-harmonic amplitude x):

* :func:`series_shift`: c x^2 with c = 3 a3/8 - 5 a2^2/12 of the law's restoring force
  (:func:`models.ladder.generic.lindstedt_coefficient`; Nayfeh & Mook 1979, Sec. 4.1.1);
* :func:`hbm_shift`: the resonance peak Omega_peak - 1 of the forced response whose peak
  amplitude is x, harmonic balance with H harmonics (:func:`models.ladder.powerlaw_ladder.hbm_peak`;
  Krack & Gross 2019);
* :func:`timeint_shift`: the stepped down-sweep integrated in time (RK4) around that peak
  (:func:`models.ladder.powerlaw_ladder.timeint_peak`), moved to x along the law's backbone slope.

The forced rungs are Python loops over x with convergence checks (slow, and compiled
per law): references, not sampler paths. A solve
that does not converge raises RuntimeError naming x; no NaN is returned.
"""

from __future__ import annotations

import math
from functools import partial
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from beadrod.models.ladder import harmonic_balance, oscillator
from beadrod.models.ladder.generic import lindstedt_coefficient
from beadrod.models.ladder.powerlaw_ladder import hbm_peak, timeint_peak

__all__ = ["ForceLaw", "oscillator_law", "quality_factor", "series_shift", "hbm_shift",
           "timeint_shift", "DYNAMIC_RUNGS", "DEFAULT_Q"]

DEFAULT_Q = 50.0
"""Q [-] of a law without a loss channel when no ``q_factor`` is given
(models.ladder.powerlaw_ladder's)."""

DYNAMIC_RUNGS = ("series", "harmonic_balance", "time_integration")
"""The rungs this module computes for any law."""

# keywords of the rungs themselves, never passed to the law's functions
_OPTIONS = ("q_factor", "harmonics", "points", "span", "settle", "steps_per_period")


class ForceLaw(oscillator.ContactLaw):
    """The normalised oscillator law g(y, y') of a :class:`models.law.ContactLaw` (module
    doc). ``params``: the law's numeric keywords (differentiable leaves)."""

    law: Any = eqx.field(static=True)
    params: dict
    delta0: Any
    f0: Any
    k0: Any
    zeta: Any = 0.0

    def _fk(self, d):
        return jax.jvp(lambda v: self.law.physics.force(v, **self.params), (d,),
                       (jnp.ones_like(d),))

    def force(self, y, yd):
        y = jnp.asarray(y, float)
        d = self.delta0 * y
        touching = d > 0.0
        f, k = self._fk(jnp.where(touching, d, self.delta0))
        total = (f + 2.0 * self.zeta * k * self.delta0 * yd) / self.f0
        total = jnp.where(f >= 0.0, jnp.maximum(total, 0.0), total)
        return jnp.where(touching, total, 0.0)

    @property
    def slope(self):
        return self.k0 * self.delta0 / self.f0


def _law_kw(kw: dict[str, Any]) -> dict[str, Any]:
    """The numeric keywords the law's force may read (scene quantities, parameters)."""
    out = {}
    for k, v in kw.items():
        if k in _OPTIONS or k in ("delta0", "omega0"):
            continue
        try:
            out[k] = jnp.asarray(v, float)
        except (TypeError, ValueError):
            continue
    return out


def oscillator_law(law: Any, *, delta0: Any, zeta: float = 0.0, **kw: Any) -> ForceLaw:
    """:class:`ForceLaw` of ``law`` at overlap delta0 [m] with damping ratio zeta [-]."""
    params = _law_kw(kw)
    d0 = jnp.asarray(delta0, float)
    f0, k0 = jax.jvp(lambda v: law.physics.force(v, **params), (d0,), (jnp.ones_like(d0),))
    if not (float(f0) > 0.0 and float(k0) > 0.0):
        raise ValueError(f"law '{law.name}': F(delta0) = {float(f0):.4g} N and "
                         f"K0 = {float(k0):.4g} N/m at delta0 = {float(d0):.4g} m; the "
                         "forced oscillator needs a compressive preload and a positive "
                         "stiffness")
    return ForceLaw(law=law, params=params, delta0=d0, f0=f0, k0=k0, zeta=jnp.asarray(zeta))


def quality_factor(law: Any, *, delta0: Any, q_factor: float | None = None,
                   **kw: Any) -> float:
    """Q [-]: the law's linear Q at omega0 if it has a loss channel, else ``q_factor``
    (default :data:`DEFAULT_Q`). omega0 [rad/s] defaults to (K0/m)^(1/2)."""
    if law.physics.linear_q is None:
        q = DEFAULT_Q if q_factor is None else float(q_factor)
    else:
        if "omega0" not in kw:
            k0 = jax.jvp(lambda v: law.physics.force(v, **_law_kw(kw)),
                         (jnp.asarray(delta0, float),), (jnp.asarray(1.0),))[1]
            kw = {**kw, "omega0": jnp.sqrt(k0 / kw["mass"])}
        q = float(law.physics.linear_q(**kw))
    if not (math.isfinite(q) and q > 2.0):
        raise ValueError(f"law '{law.name}': Q = {q:.4g}; the forced rungs need a finite "
                         "Q > 2 (a resonance peak to track)")
    return q


def _points(x: Any, delta0: Any) -> tuple[np.ndarray, np.ndarray]:
    xs, d0 = np.broadcast_arrays(np.asarray(x, float), np.asarray(delta0, float))
    if not np.all(np.isfinite(xs) & (xs >= 0.0)):
        raise ValueError(f"amplitudes x must be finite and >= 0 (got {xs.ravel().tolist()})")
    return xs, d0


def series_shift(law: Any, x: Any, *, delta0: Any, **kw: Any) -> jnp.ndarray:
    """Rung 'series': Delta f/f0 = c x^2, c from the law's restoring force (module doc)."""
    kw = {k: v for k, v in kw.items() if k not in _OPTIONS}
    coef = jnp.vectorize(lambda d: lindstedt_coefficient(law, delta0=d, **kw))(
        jnp.asarray(delta0, float))
    return coef * jnp.square(jnp.asarray(x, float))


@partial(jax.jit, static_argnames=("harmonics",))
def _hbm_backbone(cons: ForceLaw, x, omega_guess, harmonics: int = 7):
    return jax.vmap(lambda xi: harmonic_balance.backbone(cons, xi, omega_guess=omega_guess,
                                            harmonics=harmonics)[0] - 1.0)(x)


def _backbone(law: Any, x: np.ndarray, d0: float, kw: dict[str, Any],
              cons: ForceLaw) -> np.ndarray:
    """Backbone Delta f/f0 at x: the law's fast path where it has one, else the HBM
    backbone (H = 7) of the conservative oscillator (the generic energy-integral
    quadrature is slow to compile; these are starting guesses and slopes)."""
    x = np.asarray(x, float)
    if "backbone" in law.physics.shifts:
        return np.asarray(law.shift(x, rung="backbone", delta0=d0, **kw), float)
    guess = 1.0 + float(series_shift(law, float(np.max(x)), delta0=d0, **kw))
    return np.asarray(_hbm_backbone(cons, jnp.asarray(x), guess), float)


def _backbone_guess(law: Any, x: float, d0: float, kw: dict[str, Any],
                    cons: ForceLaw) -> float:
    """1 + the backbone shift at x (1 + the series where that is not finite): the start
    of the HBM backbone solve."""
    b = float(_backbone(law, np.asarray([x]), d0, kw, cons)[0])
    if not math.isfinite(b):
        b = float(series_shift(law, x, delta0=d0, **kw))
    return 1.0 + b


def _peak(law, x, d0, kw, q, harmonics):
    osc = oscillator_law(law, delta0=d0, zeta=0.5 / q, **kw)
    cons = oscillator_law(law, delta0=d0, **kw)
    try:
        return osc, cons, hbm_peak(osc, cons, x, harmonics=harmonics,
                                   omega_guess=_backbone_guess(law, x, d0, kw, cons))
    except RuntimeError as exc:
        raise RuntimeError(f"law '{law.name}', harmonic balance (H = {harmonics}, Q = "
                           f"{q:.4g}): {exc}") from None


def hbm_shift(law: Any, x: Any, *, delta0: Any, q_factor: float | None = None,
              harmonics: int = 3, **kw: Any) -> np.ndarray:
    """Rung 'harmonic_balance': Omega_peak - 1 of the forced response whose resonance peak
    has first-harmonic amplitude x, H = ``harmonics`` (default 3, as models.ladder.powerlaw_ladder:
    H = 7
    is closer to time integration, by ~1e-4 at x = 0.8, but a solve costs far more and
    converges less often past contact loss) (module doc). x = 0 is solved at
    x = 1e-6: the linear peak, Omega = (1 - 2 zeta^2)^(-1/2), about 1/(4 Q^2) above 1."""
    kw = {k: v for k, v in kw.items() if k not in _OPTIONS}
    xs, d0 = _points(x, delta0)
    out = np.empty(xs.shape)
    for i in np.ndindex(xs.shape):
        q = quality_factor(law, delta0=d0[i], q_factor=q_factor, **kw)
        _, _, (om, _, _) = _peak(law, max(float(xs[i]), 1e-6), float(d0[i]), kw, q, harmonics)
        out[i] = om - 1.0
    return out


def timeint_shift(law: Any, x: Any, *, delta0: Any, q_factor: float | None = None,
                  points: int = 13, span: float = 0.06, settle: int | None = None,
                  steps_per_period: int = 128, **kw: Any) -> np.ndarray:
    """Rung 'time_integration': the stepped down-sweep's resonance (RK4, ``points``
    frequencies over +-``span``/Q, ``settle`` periods each, default 2 Q), driven at the
    E for which harmonic balance (H = 3) puts the peak amplitude at x. The measured peak
    amplitude x_TI differs slightly from x; the result is moved to x along the law's
    backbone slope: shift_TI + (d backbone/dx)(x_TI) (x - x_TI) (as
    models.ladder.powerlaw_ladder)."""
    kw = {k: v for k, v in kw.items() if k not in _OPTIONS}
    xs, d0 = _points(x, delta0)
    out = np.empty(xs.shape)
    for i in np.ndindex(xs.shape):
        xv, dv = max(float(xs[i]), 1e-6), float(d0[i])
        q = quality_factor(law, delta0=dv, q_factor=q_factor, **kw)
        osc, cons, peak = _peak(law, xv, dv, kw, q, 3)
        try:
            om, x_ti = timeint_peak(osc, peak, q, points=points, span=span, settle=settle,
                                    steps=steps_per_period)
        except RuntimeError as exc:
            raise RuntimeError(f"law '{law.name}', time integration at x = {xv}: {exc}") \
                from None
        h = 1e-4
        b = _backbone(law, np.asarray([x_ti + h, x_ti - h]), dv, kw, cons)
        val = om - 1.0 + (b[0] - b[1]) / (2 * h) * (xv - x_ti)
        if not math.isfinite(val):
            raise RuntimeError(f"law '{law.name}', time integration at x = {xv}: no finite "
                               f"resonance (Omega = {om}, x_TI = {x_ti})")
        out[i] = val
    return out
