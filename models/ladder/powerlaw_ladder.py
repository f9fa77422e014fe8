"""The accuracy ladder: Delta f/f0 at first-harmonic amplitude x, one function per rung.

Common signature ``rungN_name(x, n=1.5, *, q_factor=50.0, **options) -> Delta f/f0``
for a power-law contact F ~ delta^n under weight preload (Hertz n = 3/2);
x = delta_a/delta0 is the first-harmonic amplitude of the overlap (models.ladder.backbone).

1. :func:`rung1_series`       Lindstedt-Poincare, leading x^2 term (models/ladder/backbone.py).
2. :func:`rung2_first_order`  averaged tangent stiffness (models/ladder/first_order.py, engineer A).
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

from beadrod.models.ladder import harmonic_balance, time_integration
from beadrod.models.ladder.backbone import backbone_shift, lindstedt_shift
from beadrod.models.ladder.oscillator import ContactLaw, PowerLaw

__all__ = [
    "rung1_series",
    "rung2_first_order",
    "rung3_backbone",
    "rung4_hbm",
    "rung5_timeint",
    "hbm_peak_solution",
    "check_peak",
    "first_peak",
    "START_PHASES",
    "hbm_peak",
    "timeint_peak",
    "RUNGS",
    "compare_rungs",
]


def rung1_series(x: ArrayLike, n: ArrayLike = 1.5, **_) -> jnp.ndarray:
    """Rung 1: (3 a3/8 - 5 a2^2/12) x^2 (Hertz: -x^2/24)."""
    return lindstedt_shift(x, n)


def rung2_first_order(x: ArrayLike, n: ArrayLike = 1.5, **_) -> jnp.ndarray:
    """Rung 2: first-order averaged stiffness (paper's estimate; Hertz: -x^2/32 + ...)."""
    return _first_order()(jnp.asarray(x, float), jnp.asarray(n, float))


_FIRST_ORDER = []


def _first_order():
    """jit of models.ladder.first_order.first_order_powerlaw, imported on first use."""
    if not _FIRST_ORDER:
        from beadrod.models.ladder.first_order import first_order_powerlaw

        _FIRST_ORDER.append(jax.jit(first_order_powerlaw))
    return _FIRST_ORDER[0]


def rung3_backbone(x: ArrayLike, n: ArrayLike = 1.5, **_) -> jnp.ndarray:
    """Rung 3: exact free-vibration backbone (includes contact loss)."""
    return backbone_shift(x, n)


def _law(n, q_factor):
    return PowerLaw(n=n, zeta=0.5 / q_factor)


START_PHASES = (0.0, 0.5 * np.pi, -0.5 * np.pi, np.pi)
"""Time shifts (drive phase [rad]) of the backbone orbit the peak solve starts from."""


@partial(jax.jit, static_argnames=("harmonics",))
def hbm_peak_solution(law: ContactLaw, conservative: ContactLaw, x: ArrayLike,
                      omega_guess: ArrayLike, harmonics: int, phase: ArrayLike = 0.0):
    """(Omega_peak, drive E, max |residual|, X) of the forced response of ``law`` whose
    peak has amplitude x: Newton on the peak system
    (:func:`models.ladder.harmonic_balance.peak_at_amplitude`)
    started from the HBM backbone of ``conservative`` (the same force without damping,
    itself started at ``omega_guess``), shifted in time by ``phase``/Omega.
    Unchecked: :func:`check_peak` checks the residual."""
    h = harmonics
    om_b, x_b = harmonic_balance.backbone(conservative, x, omega_guess=omega_guess, harmonics=h)
    k = jnp.arange(1, h + 1)
    a, b = x_b[1::2], x_b[2::2]      # q(theta) -> q(theta + phase), harmonic by harmonic
    c, s = jnp.cos(k * phase), jnp.sin(k * phase)
    start = x_b.at[1::2].set(a * c + b * s).at[2::2].set(b * c - a * s)
    om, e, coeffs = harmonic_balance.peak_at_amplitude(law, x, omega_guess=om_b, x_guess=start,
                                          harmonics=h)
    res = jnp.max(jnp.abs(harmonic_balance.residual(coeffs, om, e, law, h)))
    return om, e, res, coeffs


def check_peak(x: float, solution) -> tuple[float, float, jnp.ndarray]:
    """(Omega_peak, E, X) of a :func:`hbm_peak_solution`; RuntimeError unless it converged
    (residual < 1e-8, E != 0, everything finite) -- never a NaN shift. E < 0 is the same
    orbit half a drive period later (theta -> theta + pi flips the sign of sin theta), so
    its Omega_peak is as good."""
    om, e, res, coeffs = solution
    ok = (float(res) < 1e-8 and abs(float(e)) > 0 and np.isfinite(float(om))
          and bool(jnp.all(jnp.isfinite(coeffs))))
    if not ok:
        raise RuntimeError(f"HBM peak solve failed at x = {x} (residual {float(res):.2e})")
    return float(om), float(e), coeffs


def first_peak(x: float, solve) -> tuple[float, float, jnp.ndarray]:
    """The first converged ``solve(phase)`` over :data:`START_PHASES` (checked).

    Past contact loss the peak system is nearly singular and Newton from the backbone
    orbit may fail; started from the same orbit shifted by a quarter or half period it
    often converges. Below contact loss the first start converges (a single solve)."""
    err = None
    for phase in START_PHASES:
        try:
            return check_peak(x, solve(jnp.asarray(phase)))
        except RuntimeError as exc:
            err = exc
    raise RuntimeError(f"{err}, from {len(START_PHASES)} starting phases") from None


def hbm_peak(law: ContactLaw, conservative: ContactLaw, x: float, *, omega_guess: float,
             harmonics: int = 3) -> tuple[float, float, jnp.ndarray]:
    """Checked :func:`hbm_peak_solution`: (Omega_peak, E, X) or RuntimeError."""
    xj, gj = jnp.asarray(x, float), jnp.asarray(omega_guess, float)
    return first_peak(x, lambda p: hbm_peak_solution(law, conservative, xj, gj, harmonics, p))


@partial(jax.jit, static_argnames=("harmonics",))
def _hbm_peak_jit(x, n, q_factor, harmonics, phase):
    return hbm_peak_solution(_law(n, q_factor), PowerLaw(n=n, zeta=0.0), x,
                             1.0 + backbone_shift(x, n), harmonics, phase)


def _hbm_peak(x, n, q_factor, harmonics, with_coeffs=False):
    """(Omega_peak, drive E) whose resonance peak has amplitude x: Newton on the peak
    system started from the conservative HBM backbone; raises if it did not converge."""
    xj, nj = jnp.asarray(x, float), jnp.asarray(n, float)
    om, e, coeffs = first_peak(x, lambda p: _hbm_peak_jit(xj, nj, q_factor, harmonics, p))
    return (om, e, coeffs) if with_coeffs else (om, e)


def rung4_hbm(x: ArrayLike, n: ArrayLike = 1.5, *, q_factor: float = 50.0,
              harmonics: int = 3, **_) -> np.ndarray:
    """Rung 4: Omega_peak - 1 of the forced response whose peak amplitude is x (HBM, H).

    Newton on (R = 0, dA/dOmega = 0 along the branch, A = x) from the conservative HBM
    backbone (:func:`models.ladder.harmonic_balance.peak_at_amplitude`; :func:`first_peak`).
    """
    return np.asarray([_hbm_peak(float(v), n, q_factor, harmonics)[0] - 1.0
                       for v in np.atleast_1d(np.asarray(x, float))])


def _state_at(coeffs, omega):
    """(q, q') at tau = 0 of the harmonic solution: a settled initial state."""
    h = (coeffs.shape[0] - 1) // 2
    k = np.arange(1, h + 1)
    return jnp.stack([coeffs[0] + jnp.sum(coeffs[1::2]), omega * jnp.sum(k * coeffs[2::2])])


def _ti_sweep(law, drive, grid, y0, settle, steps, use_scipy, rtol):
    if use_scipy:
        sw = time_integration.swept_sine_scipy(law, float(drive), grid, settle_periods=settle,
                                      measure_periods=2, samples_per_period=steps, rtol=rtol,
                                      atol=rtol * 1e-2, state0=np.asarray(y0))
    else:
        sw = time_integration.swept_sine(law, drive, grid, steps_per_period=steps,
                                      settle_periods=settle,
                                measure_periods=2, state0=y0)
    amp = np.asarray(sw.amplitude)
    # keep the branch the down sweep rides until it falls off at the fold
    drop = np.nonzero(amp[1:] < 0.9 * amp[:-1])[0]
    return amp[: drop[0] + 1] if drop.size else amp


def timeint_peak(law: ContactLaw, peak: tuple[float, float, jnp.ndarray], q_factor: float, *,
                 points: int = 13, span: float = 0.06, settle: int | None = None,
                 steps: int = 128, use_scipy: bool = False,
                 rtol: float = 1e-8) -> tuple[float, float]:
    """(Omega, x) of the resonance a stepped down-sweep of ``law`` measures.

    ``peak`` = (Omega_peak, E, X) of the H = 3 harmonic balance (:func:`hbm_peak`): the
    drive E and the starting state on the upper branch; ``points`` frequencies over
    +-``span``/Q around Omega_peak, each settled for ``settle`` periods (default 2 Q),
    lock-in over 2 periods, then a pass 12x finer around the largest reading; the
    resonance is the parabola through it and its neighbours
    (:func:`models.ladder.time_integration.resonance`).
    RuntimeError if a reading is not finite.
    """
    settle = int(2 * q_factor) if settle is None else settle
    om_pk, drive, x_pk = peak
    h = 2.0 * span / q_factor / (points - 1)
    start = om_pk + span / q_factor
    for _ in range(2):          # coarse pass, then a pass 12x finer around the maximum
        grid = start - h * np.arange(points)      # down sweep
        coeffs = harmonic_balance.solve(law, drive, grid[0], x_pk, harmonics=3)   # upper branch
        y0 = _state_at(coeffs, grid[0])
        amp = _ti_sweep(law, drive, grid, y0, settle, steps, use_scipy, rtol)
        if not np.all(np.isfinite(amp)):
            raise RuntimeError(f"time integration gave a non-finite amplitude near Omega = "
                               f"{om_pk:.6g} (drive E = {drive:.3g})")
        i = int(np.argmax(amp))
        start, h = grid[max(i - 1, 0)], 2.0 * h / (points - 1)
    g = grid[: amp.size]
    om_ti, x_ti = time_integration.resonance(g, amp) if amp.size >= 3 else (g[i], amp[i])
    return float(om_ti), float(x_ti)


def _rung5_one(x, n, q_factor, *, points, span, settle, steps, use_scipy=False, rtol=1e-8):
    # drive and starting state from H = 3 (cheap; the sweep settles the rest and the
    # amplitude mismatch is corrected along the backbone slope)
    peak = _hbm_peak(x, n, q_factor, 3, with_coeffs=True)
    return timeint_peak(_law(n, q_factor), peak, q_factor, points=points, span=span,
                        settle=settle, steps=steps, use_scipy=use_scipy, rtol=rtol)


def rung5_timeint(x: ArrayLike, n: ArrayLike = 1.5, *, q_factor: float = 50.0,
                  points: int = 13, span: float = 0.06, settle: int | None = None,
                  steps_per_period: int = 128, use_scipy: bool = False,
                  rtol: float = 1e-8, **_) -> np.ndarray:
    """Rung 5: stepped down-sweep by time integration around the peak.

    The drive is the one for which harmonic balance (H = 3) puts the peak amplitude at x;
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
