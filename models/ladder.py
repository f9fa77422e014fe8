"""The accuracy ladder: Delta f/f0 at first-harmonic amplitude x, one function per rung.

Common signature ``rungN_name(x, n=1.5, *, q_factor=50.0, **options) -> Delta f/f0``
for a power-law contact F ~ delta^n under weight preload (Hertz n = 3/2);
x = delta_a/delta0 is the first-harmonic amplitude of the overlap (DESIGN.md Sec. 3).

1. :func:`rung1_series`       Lindstedt-Poincare, leading x^2 term (models/backbone.py).
2. :func:`rung2_first_order`  averaged tangent stiffness (models/shift.py, engineer A).
3. :func:`rung3_backbone`     exact conservative backbone, energy integral.
4. :func:`rung4_hbm`          forced, damped harmonic balance (H harmonics): the resonance
                              peak frequency when the drive is set so the peak amplitude is x.
5. :func:`rung5_timeint`      the stepped swept sine integrated in time (RK4) around the
                              peak, read out as an analyser would (max of the lock-in sweep).

Rungs 1-3 are conservative (no Q); rungs 4-5 describe the driven experiment with a
stiffness-proportional damping of low-drive quality factor ``q_factor`` (their peak
differs from the backbone by O(1/Q^2) terms, which the ladder shows).
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from . import hbm, timeint
from .backbone import backbone_shift, lindstedt_shift
from .oscillator import PowerLaw

__all__ = [
    "rung1_series",
    "rung2_first_order",
    "rung3_backbone",
    "rung4_hbm",
    "rung5_timeint",
    "RUNGS",
    "compare_rungs",
]


def rung1_series(x: ArrayLike, n: ArrayLike = 1.5, **_) -> jnp.ndarray:
    """Rung 1: (3 a3/8 - 5 a2^2/12) x^2 (Hertz: -x^2/24)."""
    return lindstedt_shift(x, n)


def rung2_first_order(x: ArrayLike, n: ArrayLike = 1.5, **_) -> jnp.ndarray:
    """Rung 2: first-order averaged stiffness (paper's estimate; Hertz: -x^2/32 + ...)."""
    from .shift import first_order_powerlaw

    return first_order_powerlaw(x, n)


def rung3_backbone(x: ArrayLike, n: ArrayLike = 1.5, **_) -> jnp.ndarray:
    """Rung 3: exact free-vibration backbone (includes contact loss)."""
    return backbone_shift(x, n)


def _law(n, q_factor):
    return PowerLaw(n=n, zeta=0.5 / q_factor)


@partial(jax.jit, static_argnames=("harmonics",))
def _hbm_peak(x, n, q_factor, harmonics):
    guess = 1.0 + backbone_shift(x, n)
    return hbm.peak_at_amplitude(_law(n, q_factor), x, omega_guess=guess, harmonics=harmonics)


def rung4_hbm(x: ArrayLike, n: ArrayLike = 1.5, *, q_factor: float = 50.0,
              harmonics: int = 3, **_) -> jnp.ndarray:
    """Rung 4: Omega_peak - 1 of the forced response whose peak amplitude is x (HBM, H)."""
    x = jnp.atleast_1d(jnp.asarray(x, float))
    om = jax.vmap(lambda v: _hbm_peak(v, jnp.asarray(n, float), q_factor, harmonics)[0])(x)
    return om - 1.0


def _state_at(coeffs, omega):
    """(q, q') at tau = 0 of the harmonic solution: a settled initial state."""
    h = (coeffs.shape[0] - 1) // 2
    k = np.arange(1, h + 1)
    return jnp.stack([coeffs[0] + jnp.sum(coeffs[1::2]), omega * jnp.sum(k * coeffs[2::2])])


def _rung5_one(x, n, q_factor, *, points, span, settle, steps, use_scipy=False, rtol=1e-8):
    law = _law(n, q_factor)
    om_pk, drive, coeffs = _hbm_peak(jnp.asarray(x, float), jnp.asarray(n, float), q_factor, 7)
    width = span / q_factor
    grid = np.asarray(om_pk) + width * np.linspace(1.0, -1.0, points)   # down sweep
    y0 = _state_at(hbm.solve(law, drive, grid[0], coeffs, harmonics=7), grid[0])
    if use_scipy:
        sw = timeint.swept_sine_scipy(law, float(drive), grid, settle_periods=settle,
                                      measure_periods=2, samples_per_period=steps, rtol=rtol,
                                      atol=rtol * 1e-2, state0=np.asarray(y0))
    else:
        sw = timeint.swept_sine(law, drive, grid, steps_per_period=steps, settle_periods=settle,
                                measure_periods=2, state0=y0)
    amp = np.asarray(sw.amplitude)
    # keep the branch the down sweep rides until it falls off at the fold
    drop = np.nonzero(amp[1:] < 0.9 * amp[:-1])[0]
    keep = slice(0, drop[0] + 1) if drop.size else slice(None)
    om_ti, x_ti = timeint.resonance(grid[keep], amp[keep])
    return float(om_ti), float(x_ti)


def rung5_timeint(x: ArrayLike, n: ArrayLike = 1.5, *, q_factor: float = 50.0,
                  points: int = 13, span: float = 0.06, settle: int | None = None,
                  steps_per_period: int = 128, use_scipy: bool = False,
                  rtol: float = 1e-8, **_) -> np.ndarray:
    """Rung 5: stepped down-sweep by time integration around the peak.

    The drive is the one for which harmonic balance (H = 7) puts the peak amplitude at x;
    ``points`` frequencies spaced over +-``span``/Q around the predicted peak, each settled
    for ``settle`` periods (default 2 Q), lock-in over 2 periods; the resonance is the
    parabola through the largest reading and its neighbours on the branch. The measured
    peak amplitude x_TI differs slightly from x; the result is moved to x along the exact
    backbone slope: shift_TI + (d backbone/dx) (x - x_TI). ``use_scipy`` runs the same
    experiment with solve_ivp (baseline).
    """
    settle = int(2 * q_factor) if settle is None else settle
    out = []
    for xv in np.atleast_1d(np.asarray(x, float)):
        om, x_ti = _rung5_one(xv, n, q_factor, points=points, span=span, settle=settle,
                              steps=steps_per_period, use_scipy=use_scipy, rtol=rtol)
        h = 1e-4
        b = np.asarray(backbone_shift(jnp.array([x_ti + h, x_ti - h]), n))
        out.append(om - 1.0 + (b[0] - b[1]) / (2 * h) * (xv - x_ti))
    return np.asarray(out)


RUNGS = {
    "1 series": rung1_series,
    "2 first order": rung2_first_order,
    "3 backbone": rung3_backbone,
    "4 HBM H=1": partial(rung4_hbm, harmonics=1),
    "4 HBM H=3": partial(rung4_hbm, harmonics=3),
    "4 HBM H=7": partial(rung4_hbm, harmonics=7),
    "5 time integration": rung5_timeint,
}
"""Every rung, cheapest first, as callables of (x, n, *, q_factor)."""


def compare_rungs(x_values: ArrayLike, n: float = 1.5, *, q_factor: float = 50.0,
                  rungs: dict | None = None, reference: str = "5 time integration") -> dict:
    """Delta f/f0 of every rung at ``x_values`` and its error against ``reference``.

    Returns {rung name: {"shift": array, "error": array}}.
    """
    x = np.atleast_1d(np.asarray(x_values, float))
    rungs = RUNGS if rungs is None else rungs
    vals = {k: np.asarray(f(jnp.asarray(x), n, q_factor=q_factor)).reshape(-1)
            for k, f in rungs.items()}
    ref = vals[reference]
    return {k: {"shift": v, "error": v - ref} for k, v in vals.items()}
