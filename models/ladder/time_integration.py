"""Time integration of the stepped swept-sine experiment (ladder rung 5).

Integrates the base-excited contact oscillator (models/ladder/oscillator.py, Eq. (*))

    q'' = -(g(1 + q, q') - 1)/s - E Omega^2 sin(Omega tau)

as a stepped-sine analyser drives it: at each frequency of the list the drive runs
``settle_periods`` whole periods (state carried over from the previous frequency; the
drive phase is continuous because every dwell is a whole number of periods), then the
first harmonic is measured by lock-in over ``measure_periods`` whole periods:
a1 = (2/N) sum q cos(Omega tau_j), b1 = (2/N) sum q sin(Omega tau_j) (rectangle rule,
exact for trigonometric polynomials of degree < N per period).
Reported: x = hypot(a1, b1) (overlap, delta_a/delta0; the convention of
models/ladder/harmonic_balance.py)
and the bead's own first harmonic hypot(E - b1, a1), that of w = E sin(Omega tau) - q.

Integrator: classical RK4, fixed ``steps_per_period`` per drive period. The contact
force is continuous but only C^0/C^1 at contact loss (F = 0 for delta <= 0), which
costs RK4 its formal order locally but not its stability; accuracy versus step count is
measured in tests/test_timeint.py and workflows/bench/accuracy.py. JAX version:
``lax.scan`` over frequencies, ``lax.fori_loop`` over steps, jit-able and vmap-able.
:func:`swept_sine_scipy` runs the same experiment with scipy's ``solve_ivp``
(adaptive DOP853/RK45) as the benchmark baseline.
"""

from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.ladder.oscillator import ContactLaw, PowerLaw, Viscoelastic, rhs

__all__ = [
    "Sweep",
    "swept_sine",
    "swept_sine_scipy",
    "up_down",
    "resonance",
    "q_factor_3db",
]


class Sweep(NamedTuple):
    """One measured sweep (arrays in the order the frequencies were visited)."""

    omega: jnp.ndarray      # (F,) Omega [-]
    cos: jnp.ndarray        # (F,) a1 of q [-]
    sin: jnp.ndarray        # (F,) b1 of q [-]
    amplitude: jnp.ndarray  # (F,) x = |first harmonic of q| = delta_a/delta0 [-]
    bead: jnp.ndarray       # (F,) |first harmonic of the bead displacement| / delta0 [-]
    state: jnp.ndarray      # (2,) final (q, q')


def _rk4(law, omega, drive, dt):
    def f(y, tau):
        return jnp.stack([y[1], rhs(y[0], y[1], tau, law=law, omega=omega, drive=drive)])

    def step(y, tau):
        k1 = f(y, tau)
        k2 = f(y + 0.5 * dt * k1, tau + 0.5 * dt)
        k3 = f(y + 0.5 * dt * k2, tau + 0.5 * dt)
        k4 = f(y + dt * k3, tau + dt)
        return y + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)

    return step


@partial(jax.jit, static_argnames=("steps_per_period", "settle_periods", "measure_periods"))
def swept_sine(law: ContactLaw, drive: ArrayLike, omegas: ArrayLike, *,
               steps_per_period: int = 128, settle_periods: int = 40,
               measure_periods: int = 8, state0: ArrayLike | None = None) -> Sweep:
    """Stepped swept sine through ``omegas`` in the given order (JAX, RK4). jit-able."""
    m = steps_per_period
    n_settle, n_meas = settle_periods * m, measure_periods * m
    y0 = jnp.zeros(2) if state0 is None else jnp.asarray(state0, float)

    def one(y, om):
        dt = 2.0 * jnp.pi / (om * m)
        step = _rk4(law, om, drive, dt)
        y = jax.lax.fori_loop(0, n_settle, lambda j, y: step(y, j * dt), y)

        def meas(j, c):
            y, sc, ss = c
            ph = om * j * dt
            return step(y, j * dt), sc + y[0] * jnp.cos(ph), ss + y[0] * jnp.sin(ph)

        y, sc, ss = jax.lax.fori_loop(n_settle, n_settle + n_meas, meas, (y, 0.0, 0.0))
        return y, (2.0 * sc / n_meas, 2.0 * ss / n_meas)

    y, (a1, b1) = jax.lax.scan(one, y0, jnp.asarray(omegas, float))
    amp = jnp.hypot(a1, b1)
    bead = jnp.hypot(drive - b1, a1)
    return Sweep(jnp.asarray(omegas, float), a1, b1, amp, bead, y)


def up_down(law: ContactLaw, drive: ArrayLike, omegas: ArrayLike, **kw) -> tuple[Sweep, Sweep]:
    """An up sweep over sorted ``omegas`` then a down sweep starting from its final state."""
    om = jnp.sort(jnp.asarray(omegas, float))
    up = swept_sine(law, drive, om, **kw)
    kw = {k: v for k, v in kw.items() if k != "state0"}
    down = swept_sine(law, drive, om[::-1], state0=up.state, **kw)
    return up, down


def resonance(omega: ArrayLike, amp: ArrayLike) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Resonance of a measured sweep: (Omega, x) at the largest amplitude, refined by a
    parabola through the maximum and its two neighbours (grid order irrelevant)."""
    order = jnp.argsort(omega)
    om, a = jnp.asarray(omega)[order], jnp.asarray(amp)[order]
    i = jnp.clip(jnp.argmax(a), 1, om.shape[0] - 2)
    x0, x1, x2 = om[i - 1], om[i], om[i + 1]
    y0, y1, y2 = a[i - 1], a[i], a[i + 1]
    d = (x0 - x1) * (x0 - x2) * (x1 - x2)
    ca = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / d
    cb = (x2**2 * (y0 - y1) + x1**2 * (y2 - y0) + x0**2 * (y1 - y2)) / d
    cc = (x1 * x2 * (x1 - x2) * y0 + x2 * x0 * (x2 - x0) * y1 + x0 * x1 * (x0 - x1) * y2) / d
    ok = ca < 0
    xv = jnp.where(ok, -cb / (2.0 * jnp.where(ok, ca, -1.0)), x1)
    xv = jnp.clip(xv, x0, x2)
    return xv, jnp.where(ok, cc - cb**2 / (4.0 * jnp.where(ok, ca, -1.0)), y1)


def q_factor_3db(omega: ArrayLike, amp: ArrayLike) -> jnp.ndarray:
    """Quality factor Omega_res / (Omega_2 - Omega_1) from the -3 dB (1/sqrt 2) points,
    located by linear interpolation on each side of the maximum (low drive only)."""
    om, a = np.asarray(omega), np.asarray(amp)
    order = np.argsort(om)
    om, a = om[order], a[order]
    i = int(np.argmax(a))
    level = a[i] / math.sqrt(2.0)
    left = np.nonzero(a[:i] < level)[0]
    right = np.nonzero(a[i:] < level)[0]
    if left.size == 0 or right.size == 0:
        raise ValueError("sweep does not reach the -3 dB level on both sides of the peak")
    j, k = left[-1], i + right[0]
    o1 = om[j] + (level - a[j]) * (om[j + 1] - om[j]) / (a[j + 1] - a[j])
    o2 = om[k - 1] + (level - a[k - 1]) * (om[k] - om[k - 1]) / (a[k] - a[k - 1])
    res, _ = resonance(om, a)
    return float(res) / (o2 - o1)


def _numpy_force(law: ContactLaw):
    """Plain-Python g(y, yd) for the scipy baseline (no JAX dispatch inside solve_ivp)."""
    if isinstance(law, PowerLaw):
        n, z = float(law.n), float(law.zeta)
        return lambda y, v: max(y**n + 2.0 * z * n * y ** (n - 1.0) * v, 0.0) if y > 0 else 0.0
    if isinstance(law, Viscoelastic):
        a, z = float(law.a_omega0), float(law.zeta)
        return lambda y, v: (max(y**1.5 + 1.5 * (a + 2.0 * z) * math.sqrt(y) * v, 0.0)
                             if y > 0 else 0.0)
    jf = jax.jit(law.force)
    return lambda y, v: float(jf(y, v))


def swept_sine_scipy(law: ContactLaw, drive: float, omegas: ArrayLike, *,
                     settle_periods: int = 40, measure_periods: int = 8,
                     samples_per_period: int = 128, rtol: float = 1e-8, atol: float = 1e-10,
                     method: str = "DOP853", state0: ArrayLike | None = None) -> Sweep:
    """The same stepped swept sine with scipy.integrate.solve_ivp (baseline, NumPy)."""
    from scipy.integrate import solve_ivp

    g = _numpy_force(law)
    s = float(law.slope)
    drive = float(drive)
    y = np.zeros(2) if state0 is None else np.asarray(state0, float)
    a1s, b1s = [], []
    for om in np.asarray(omegas, float):
        period = 2.0 * np.pi / om
        f2 = drive * om * om

        def f(t, u, om=om, f2=f2):
            return [u[1], -(g(1.0 + u[0], u[1]) - 1.0) / s - f2 * math.sin(om * t)]

        t_s = settle_periods * period
        y = solve_ivp(f, (0.0, t_s), y, method=method, rtol=rtol, atol=atol).y[:, -1]
        n = measure_periods * samples_per_period
        t_ev = t_s + period * np.arange(n + 1) / samples_per_period
        sol = solve_ivp(f, (t_s, t_ev[-1]), y, method=method, rtol=rtol, atol=atol,
                        t_eval=t_ev)
        q = sol.y[0, :-1]
        ph = om * t_ev[:-1]
        a1s.append(2.0 * np.mean(q * np.cos(ph)))
        b1s.append(2.0 * np.mean(q * np.sin(ph)))
        y = sol.y[:, -1]
    a1, b1 = np.array(a1s), np.array(b1s)
    return Sweep(np.asarray(omegas, float), a1, b1, np.hypot(a1, b1), np.hypot(drive - b1, a1),
                 y)
